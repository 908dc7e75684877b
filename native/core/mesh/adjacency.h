// Connectivity of an indexed triangle mesh in compressed sparse row (CSR) form: vertex -> incident triangles and
// vertex -> one-ring neighbours. One flat array per relation (no per-vertex containers), built in parallel, and
// every row sorted ascending, so the result is the same for any thread count and algorithms iterating it are
// deterministic. Shared by topology checks, decimation, smoothing, normals and the quality report.
#pragma once
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "base/uninitialized_vector.h"
#include "mesh/mesh.h"

namespace meniscus {

// Row r holds items[offsets[r] .. offsets[r + 1]). The arrays leave resized elements unwritten (every builder fills
// them completely, in parallel: base/uninitialized_vector.h).
struct CsrList {
    UninitializedVector<int64_t> offsets{0};
    UninitializedVector<int32_t> items;

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

// Throws InputError ("where: the adjacency does not belong to this mesh") unless `list` has a row per vertex.
void require_row_per_vertex(const CsrList& list, std::size_t vertex_count, const std::string& where);

// The items 0 .. n-1 grouped by keys[i] (each in [0, groups)), ascending within a group: a counting sort by key,
// the same rows at any thread count (in parallel: atomic counters, then every row sorted).
CsrList group_by_key(const int32_t* keys, int64_t n, int32_t groups, int threads);

CsrList build_vertex_triangles(const TriMesh& mesh, int threads);
CsrList build_vertex_neighbours(const TriMesh& mesh, const CsrList& vertex_triangles, int threads);
MeshAdjacency build_adjacency(const TriMesh& mesh, int threads);
// The distinct other vertices of v's triangles fan[0 .. fan_size) (ids into tris, 3 per triangle), ascending, written
// to out (room for 2 * fan_size); returns their count. One row of build_vertex_neighbours.
int32_t collect_vertex_neighbours(const int32_t* tris, int32_t v, const int32_t* fan, int32_t fan_size, int32_t* out);

// The edges of one vertex: for vertex v, every (u, t, direction) where triangle t contains the edge (v, u) with
// u > v, direction +1 when t runs v -> u and -1 when it runs u -> v; sorted by u, then t. Each undirected edge is
// seen from its smaller vertex only, so a parallel loop over vertices visits every edge once. Triangles with a
// repeated index are skipped.
struct EdgeIncidence {
    int32_t other;
    int32_t triangle;
    int32_t direction;
};
void upper_edge_incidences(const TriMesh& mesh, const CsrList& vertex_triangles, int32_t v, std::vector<EdgeIncidence>& out);

// Calls visit(first, last) for every run of incidences that share the same other vertex (one undirected edge and
// its triangles), in order.
template <class Visit>
void for_each_edge(const std::vector<EdgeIncidence>& incidences, Visit&& visit) {
    for (std::size_t i = 0; i < incidences.size();) {
        std::size_t j = i;
        while (j < incidences.size() && incidences[j].other == incidences[i].other) ++j;
        visit(incidences.data() + i, incidences.data() + j);
        i = j;
    }
}

}  // namespace meniscus
