// "Mesh cleanup" (paper Sec. 3.3, after Moore and Warren): marching cubes puts tiny triangles around the lattice
// points where the surface passes close by. One-ring neighbours that share their nearest lattice point are merged
// into one vertex at their average position, with legal half-edge collapses (collapse.h).
#pragma once
#include <cstddef>
#include <cstdint>
#include <vector>

#include "mesh/mesh.h"

namespace meniscus {

// Lattice of spacing cube_edge anchored at the origin (the marching-cubes grid). snap_distance < 0: all vertices
// take part; otherwise only those within snap_distance * cube_edge of their lattice point. Normals and attributes
// of a merged vertex become the means over the vertices merged into it. Returns the number of vertices removed;
// the same result for any thread count. `pinned` (optional, one flag per vertex): vertices that take no part (those
// on a container's wall stay exactly where they are).
std::size_t mesh_cleanup(TriMesh& mesh, double cube_edge, double snap_distance, int threads, const std::vector<uint8_t>* pinned = nullptr);

}  // namespace meniscus
