// Stray blobs removed: connected pieces of the surface made by fewer particles than a minimum, or enclosing less
// than a minimum volume (splashsurf #230 asks for it). Off by default, so droplets stay. Runs on the marching-cubes
// mesh, before anything else changes it: the rule is stable across frames because a droplet keeps its particle
// count, and the removed volume is the pieces' own.
#pragma once
#include <cstddef>

#include "mesh/mesh.h"
#include "surface/reconstruction.h"

namespace meniscus {

struct StrayRemoval {
    std::size_t components = 0;  // pieces removed
    std::size_t particles = 0;   // particles in their clusters
    double volume = 0.0;         // volume they enclosed (scene units cubed)
};

// Removes the pieces of the mesh whose particle cluster (sph/clusters.h, kernel support as the distance) has fewer
// than min_particles particles, or whose enclosed volume is below min_volume particle volumes (4/3 pi r^3 each).
// 0 turns a rule off. Enclosed bubbles (negative volume) are never removed: they are holes in the fluid, not blobs.
StrayRemoval remove_stray_components(TriMesh& mesh, const SurfaceReconstruction& reconstruction, int min_particles,
                                     double min_volume, int threads);

}  // namespace meniscus
