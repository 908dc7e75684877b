// The surface Mantaflow itself meshes for a FLIP liquid (its "improved particle level set"), rebuilt from the cache's
// particles and the fluid domain: on the domain's grid refined by the Mesh panel's Upres Factor,
//   - per cell centre x, the particles within 2 R weighted w = max(0, 1 - |x - p|^2 / (4 R^2)) (Zhu and Bridson),
//     R = 0.5 sqrt(3) (mesh particle radius + 0.01) cells; phi = |x - mean p| - R, R where nothing weighs;
//   - Solenthaler's correction: where the mean position's Jacobian has its largest eigenvalue above concave_lower
//     the radius shrinks (to 0 at concave_upper, smoothstep); phi capped at R;
//   - smoothing passes (7-point means; the negative ones only lower), phi = 0.5 on the grid's outer layer;
//   - joined with the simulation's level set, which the cache does not hold: the cells of the narrow-band
//     classification (sph/interior_fill.h) that lie deeper than 2.5 solver cells under its air get phi <= -1 (as
//     Mantaflow joins its grid level set shrunk by a cell);
//   - Mantaflow's simple extrapolation inside (band + 2 cells) and outside (3 cells), phi = 0.5 on the outer
//     Upres Factor layers, marching cubes at 0.
// Vertex attributes are the same weighted particle mean at each vertex (the heaviest particle's for whole numbers);
// where no particle weighs (a wall under the band), the particle's nearest through the grid.
#pragma once
#include <array>
#include <cstddef>
#include <vector>

#include "base/attributes.h"
#include "mesh/mesh.h"
#include "sph/fluid_domain.h"
#include "sph/particles.h"

namespace meniscus {

struct ParticleLevelSetSurface {
    TriMesh mesh;                      // world space, counter-clockwise seen from outside, no normals
    std::array<int, 3> resolution{};   // of the refined grid
    std::size_t joined_cells = 0;      // refined cells joined as the simulation's level set
};

// InputError naming the field (fluid_domain.mesh_upres, ...) when Mantaflow's mesh settings are out of range.
void validate_mesh_settings(const FluidDomain& domain);

// The mesh, the same for any thread count. ResourceError beyond the memory budget (0: the default budget).
ParticleLevelSetSurface particle_level_set_surface(const PositionsView& positions, const std::vector<AttributeInput>& attributes,
                                                   const FluidDomain& domain, int threads, std::size_t memory_budget_bytes);

}  // namespace meniscus
