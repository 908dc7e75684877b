// Connectivity of an indexed triangle mesh in compressed sparse row (CSR) form: vertex -> incident triangles,
// vertex -> one-ring neighbours and undirected edge -> incident triangles. One flat array per relation (no
// per-vertex containers), built in parallel, and every row sorted ascending, so the result is the same for any
// thread count and algorithms iterating it are deterministic. Shared by topology checks, decimation, smoothing,
// normals and the quality report.
#pragma once
#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "mesh/mesh.h"
#include "base/parallel.h"

namespace meniscus {

// Row r holds items[offsets[r] .. offsets[r + 1]).
struct CsrList {
    std::vector<int64_t> offsets{0};
    std::vector<int32_t> items;

    std::size_t rows() const { return offsets.size() - 1; }
    int64_t begin(std::size_t r) const { return offsets[r]; }
    int64_t end(std::size_t r) const { return offsets[r + 1]; }
    int32_t size(std::size_t r) const { return static_cast<int32_t>(offsets[r + 1] - offsets[r]); }
    const int32_t* row(std::size_t r) const { return items.data() + offsets[r]; }
};

struct MeshAdjacency {
    CsrList vertex_triangles;   // triangles using the vertex, ascending (a triangle with a repeated index once)
    CsrList vertex_neighbours;  // distinct vertices sharing a triangle with the vertex, ascending (never itself)

    int32_t valence(std::size_t v) const { return vertex_neighbours.size(v); }
};

// Undirected edges (a < b), ordered by a then b, and their incident triangles (ascending).
struct EdgeMap {
    std::vector<int32_t> edge_vertices;       // 2 * E: a, b
    std::vector<int64_t> vertex_edge_offsets;  // V + 1: edges whose smaller vertex is a are [off[a], off[a + 1])
    CsrList edge_triangles;

    std::size_t num_edges() const { return edge_vertices.size() / 2; }
};

// Throws InputError (naming `where`) when array sizes are not multiples of 3, an index is out of range, normals
// are neither empty nor one per vertex, or an attribute does not hold one value tuple per vertex.
void validate_mesh_arrays(const TriMesh& mesh, const std::string& where);

CsrList build_vertex_triangles(const TriMesh& mesh, int threads);
CsrList build_vertex_neighbours(const TriMesh& mesh, const CsrList& vertex_triangles, int threads);
MeshAdjacency build_adjacency(const TriMesh& mesh, int threads);
// The distinct other vertices of v's triangles fan[0 .. fan_size) (ids into tris, 3 per triangle), ascending, written
// to out (room for 2 * fan_size); returns their count. One row of build_vertex_neighbours.
int32_t collect_vertex_neighbours(const int32_t* tris, int32_t v, const int32_t* fan, int32_t fan_size, int32_t* out);
EdgeMap build_edge_map(const MeshAdjacency& adjacency, int threads);

// Edges of one vertex without building an EdgeMap: for vertex v, every (u, t, direction) where triangle t
// contains the edge (v, u) with u > v, direction +1 when t runs v -> u and -1 when it runs u -> v; sorted by u,
// then t. Each undirected edge is seen from its smaller vertex only, so a parallel loop over vertices visits
// every edge once. Triangles with a repeated index are skipped.
struct EdgeIncidence {
    int32_t other;
    int32_t triangle;
    int32_t direction;
};
void upper_edge_incidences(const TriMesh& mesh, const CsrList& vertex_triangles, int32_t v, std::vector<EdgeIncidence>& out);

// Index of edge (a, b) (either order), or -1 when a and b share no triangle.
int64_t find_edge(const EdgeMap& edges, int32_t a, int32_t b);

// One Jacobi step of the uniform umbrella operator on 3-float positions:
// out_i = in_i + factor * w_i * (mean_{j in N(i)} in_j - in_i), with w_i = 1 when weights is null. Vertices
// without neighbours keep their position. Offsets summed in float per vertex, independent of the thread count.
void umbrella_step(const CsrList& neighbours, const float* in, float* out, const float* weights, double factor,
                   int threads);

// Single-/double-vertex barnacle configurations (paper Sec. 3.3) counted on a prebuilt adjacency; defined in
// decimation.cpp next to the detection used by decimate_barnacles.
std::size_t count_single_vertex_configurations(const MeshAdjacency& adjacency, int threads);
std::size_t count_double_vertex_configurations(const MeshAdjacency& adjacency, int threads);

// Calls body(begin, end) for consecutive blocks of [0, n) in parallel; lets a body reuse scratch buffers for a
// whole block instead of allocating per element.
template <class F>
void parallel_blocks(int64_t n, int threads, int64_t block, F&& body) {
    if (n <= 0) return;
    const int64_t blocks = (n + block - 1) / block;
    parallel_for(blocks, threads, [&](int64_t b) { body(b * block, std::min(n, (b + 1) * block)); });
}

}  // namespace meniscus
