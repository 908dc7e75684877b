// Decimation of the marching-cubes "barnacle" configurations (paper Sec. 3.3): a vertex of valence 4 whose
// neighbours' valences sum to 20 (single vertex), or two adjacent vertices of valence 5 with two shared valence-6
// neighbours (double vertex), both tiny triangles hugging a grid point. Each configuration's one-ring is collapsed
// into its centre(s) with legal half-edge collapses (collapse.h); the centres stay where they are.
#pragma once
#include <cstddef>
#include <cstdint>
#include <vector>

#include "mesh/adjacency.h"
#include "mesh/mesh.h"

namespace meniscus {

// Removes the single- and double-vertex configurations and returns how many were removed. Normals and attributes
// of the surviving vertices are kept. With final_adjacency, also hands over the adjacency of the resulting mesh
// when its last detection pass already built it (left empty otherwise), so the caller need not build it again.
// The same result for any thread count. `pinned` (optional, one flag per vertex): configurations touching a pinned
// vertex (one on a container's wall) are left alone, so no wall vertex is collapsed away.
std::size_t decimate_barnacles(TriMesh& mesh, int threads, MeshAdjacency* final_adjacency = nullptr,
                               const std::vector<uint8_t>* pinned = nullptr);

// The configurations present (for reports and tests), on a mesh or on its prebuilt adjacency.
std::size_t count_single_vertex_configurations(const TriMesh& mesh);
std::size_t count_double_vertex_configurations(const TriMesh& mesh);
std::size_t count_single_vertex_configurations(const MeshAdjacency& adjacency, int threads);
std::size_t count_double_vertex_configurations(const MeshAdjacency& adjacency, int threads);

}  // namespace meniscus
