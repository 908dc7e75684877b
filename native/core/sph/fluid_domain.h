// What a grid-based liquid solver's cache says about its domain (Mantaflow today): where its grid lies in the world,
// which borders are walls, which way gravity pulls and how deep its narrow band of particles reaches. Readers of such
// caches fill what the files hold; the add-on fills the rest from the domain's settings. The narrow-band fill uses it
// to tell the liquid's interior from the air around a shell of particles.
#pragma once
#include <array>
#include <vector>

namespace meniscus {

struct FluidDomain {
    // World position of grid index coordinates (i, j, k), cell corners at integers: world = origin + i*axes[0] +
    // j*axes[1] + k*axes[2]; each axis is one cell's edge in world units (rotation and scale included).
    std::array<double, 3> origin{0.0, 0.0, 0.0};
    std::array<std::array<double, 3>, 3> axes{{{1.0, 0.0, 0.0}, {0.0, 1.0, 0.0}, {0.0, 0.0, 1.0}}};
    std::array<int, 3> resolution{0, 0, 0};       // cells per axis
    // Borders in the order -x, +x, -y, +y, -z, +z of the grid: true where the liquid cannot leave (a wall).
    std::array<bool, 6> closed_borders{true, true, true, true, true, true};
    std::array<double, 3> gravity{0.0, 0.0, -1.0};  // world direction (unit) in which gravity pulls
    double band_width_cells = 0.0;  // particles are kept only this deep under the surface; 0: the whole liquid
    // Solid obstacles as world-space triangle soups (x y z of each corner, 9 floats per triangle); may be empty.
    std::vector<std::vector<float>> obstacles;
    // Mantaflow's Mesh panel (Blender's FluidDomainSettings, defaults Blender's): the level set it meshes lies on the
    // domain's grid refined by mesh_upres; the particle radius is in the refined grid's cells (of which Mantaflow
    // takes half a cell diagonal, plus 1 %); smoothing passes that average and that only lower; the concavity
    // correction's eigenvalue range (surface/particle_level_set.h). The caches do not hold them.
    int mesh_upres = 2;
    double mesh_particle_radius = 2.0;
    int mesh_smoothen_pos = 1;
    int mesh_smoothen_neg = 1;
    double mesh_concave_lower = 0.4;
    double mesh_concave_upper = 3.5;
    // The domain object's matrix that places the grid (column-major, Blender's object_to_world): a cache reader sets
    // the one the frame was simulated with. The fill does not read it; the add-on moves a frame read from the cache
    // to where the domain is now, as Blender's own fluid mesh follows the domain object.
    std::array<double, 16> object_to_world{1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};
};

}  // namespace meniscus
