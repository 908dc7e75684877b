#include "mesh/topology.h"

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "base/disjoint_sets.h"
#include "base/parallel.h"
#include "mesh/adjacency.h"
#include "mesh/geometry.h"

namespace meniscus {

bool triangle_has_zero_area(const float* vertices, const int32_t* triangle) { return is_zero(triangle_cross(vertices, triangle)); }

namespace {

// The fan of triangles around v is one disk when its link (edge next(v) -> prev(v) of every triangle) is a
// single cycle, or a single path at a boundary: every link vertex has at most two link edges and the link graph
// is connected. A bow-tie (two fans meeting at v) has two components.
struct VertexScratch {
    std::vector<int32_t> link_vertices, degree;
    DisjointSets link_components;
    std::vector<EdgeIncidence> edges;
};

bool fan_is_single_disk(const TriMesh& mesh, const CsrList& vt, int32_t v, VertexScratch& s) {
    const int32_t* tris = mesh.triangles.data();
    s.link_vertices.clear();
    for (int64_t k = vt.begin(v); k < vt.end(v); ++k) {
        const int32_t* t = tris + 3 * static_cast<int64_t>(vt.items[k]);
        for (int c = 0; c < 3; ++c)
            if (t[c] != v) s.link_vertices.push_back(t[c]);
    }
    std::sort(s.link_vertices.begin(), s.link_vertices.end());
    s.link_vertices.erase(std::unique(s.link_vertices.begin(), s.link_vertices.end()), s.link_vertices.end());
    const int32_t n = static_cast<int32_t>(s.link_vertices.size());
    auto local = [&](int32_t u) {
        return static_cast<int32_t>(std::lower_bound(s.link_vertices.begin(), s.link_vertices.end(), u) - s.link_vertices.begin());
    };
    s.degree.assign(static_cast<std::size_t>(n), 0);
    s.link_components.reset(static_cast<std::size_t>(n));
    int32_t components = n;
    for (int64_t k = vt.begin(v); k < vt.end(v); ++k) {
        const int32_t* t = tris + 3 * static_cast<int64_t>(vt.items[k]);
        const int corner = corner_of(t, v);
        const int32_t a = local(t[(corner + 1) % 3]), b = local(t[(corner + 2) % 3]);
        if (++s.degree[a] > 2 || ++s.degree[b] > 2) return false;
        if (s.link_components.unite(a, b)) --components;
    }
    return components == 1;
}

}  // namespace

std::string MeshCheck::summary() const {
    std::string problems;
    auto add = [&](std::size_t count, const char* singular, const char* plural) {
        if (count == 0) return;
        if (!problems.empty()) problems += ", ";
        problems += std::to_string(count) + " " + (count == 1 ? singular : plural);
    };
    add(boundary_edges, "boundary edge", "boundary edges");
    add(non_manifold_edges, "non-manifold edge", "non-manifold edges");
    add(non_manifold_vertices, "non-manifold vertex", "non-manifold vertices");
    add(inconsistent_edges, "inconsistently oriented edge", "inconsistently oriented edges");
    add(degenerate_triangles, "degenerate triangle", "degenerate triangles");
    add(non_finite_vertices, "non-finite vertex", "non-finite vertices");
    std::string text = problems.empty() ? std::string("closed, manifold, oriented") : problems;
    if (unreferenced_vertices > 0)
        text += "; " + std::to_string(unreferenced_vertices) +
                (unreferenced_vertices == 1 ? " unreferenced vertex" : " unreferenced vertices");
    return text;
}

namespace {

// What the pass over the vertices finds: each undirected edge is examined at its smaller vertex (triangle count
// and traversal directions), each vertex's fan is checked for being a single disk.
struct FanAndEdgeCounts {
    std::size_t boundary_edges = 0, non_manifold_edges = 0, inconsistent_edges = 0, non_manifold_vertices = 0,
                unreferenced_vertices = 0;
};

FanAndEdgeCounts count_fan_and_edge_problems(const TriMesh& mesh, const CsrList& vt, int threads) {
    constexpr int64_t kBlock = 4096;
    return ordered_block_reduce(
        static_cast<int64_t>(mesh.num_vertices()), threads, kBlock, FanAndEdgeCounts{},
        [&](int64_t begin, int64_t end, FanAndEdgeCounts& c) {
            VertexScratch s;
            for (int64_t v = begin; v < end; ++v) {
                if (vt.size(v) == 0) {
                    ++c.unreferenced_vertices;
                    continue;
                }
                if (!fan_is_single_disk(mesh, vt, static_cast<int32_t>(v), s)) ++c.non_manifold_vertices;
                upper_edge_incidences(mesh, vt, static_cast<int32_t>(v), s.edges);
                for_each_edge(s.edges, [&](const EdgeIncidence* first, const EdgeIncidence* last) {
                    int32_t direction = 0;
                    for (const EdgeIncidence* e = first; e != last; ++e) direction += e->direction;
                    if (last - first == 1) ++c.boundary_edges;
                    else if (last - first > 2) ++c.non_manifold_edges;
                    else if (direction != 0) ++c.inconsistent_edges;  // consistent: one runs v -> u, the other u -> v
                });
            }
        },
        [](FanAndEdgeCounts& total, const FanAndEdgeCounts& c) {
            total.boundary_edges += c.boundary_edges;
            total.non_manifold_edges += c.non_manifold_edges;
            total.inconsistent_edges += c.inconsistent_edges;
            total.non_manifold_vertices += c.non_manifold_vertices;
            total.unreferenced_vertices += c.unreferenced_vertices;
        });
}

TriMesh without_repeated_index_triangles(const TriMesh& mesh) {
    TriMesh filtered;
    filtered.vertices = mesh.vertices;
    filtered.triangles.reserve(mesh.triangles.size());
    for (std::size_t t = 0; t < mesh.num_triangles(); ++t) {
        const int32_t* c = &mesh.triangles[3 * t];
        if (!has_repeated_index(c)) filtered.triangles.insert(filtered.triangles.end(), c, c + 3);
    }
    return filtered;
}

std::size_t count_unreferenced_vertices(const TriMesh& mesh) {
    std::vector<uint8_t> used(mesh.num_vertices(), 0);
    for (int32_t v : mesh.triangles) used[v] = 1;
    return static_cast<std::size_t>(std::count(used.begin(), used.end(), uint8_t(0)));
}

}  // namespace

MeshCheck check_mesh(const TriMesh& mesh) {
    if (!mesh.quads.empty()) return check_mesh(triangulated(mesh));  // a quad is closed/manifold as its two halves are
    validate_mesh_arrays(mesh, "check_mesh");
    const int threads = 0;
    const int32_t* tris = mesh.triangles.data();
    const float* vertices = mesh.vertices.data();
    MeshCheck check;
    // One pass: a repeated index or else exactly zero area (the first is needed on its own below).
    struct Degenerate {
        std::size_t repeated_index = 0, zero_area = 0;
    };
    constexpr int64_t kTriangleBlock = 1 << 16;
    const Degenerate degenerate = ordered_block_reduce(
        static_cast<int64_t>(mesh.num_triangles()), threads, kTriangleBlock, Degenerate{},
        [&](int64_t begin, int64_t end, Degenerate& d) {
            for (int64_t t = begin; t < end; ++t) {
                if (has_repeated_index(tris + 3 * t)) ++d.repeated_index;
                else if (triangle_has_zero_area(vertices, tris + 3 * t)) ++d.zero_area;
            }
        },
        [](Degenerate& total, const Degenerate& d) {
            total.repeated_index += d.repeated_index;
            total.zero_area += d.zero_area;
        });
    const std::size_t repeated = degenerate.repeated_index;
    check.degenerate_triangles = degenerate.repeated_index + degenerate.zero_area;
    check.non_finite_vertices = parallel_count(static_cast<int64_t>(mesh.num_vertices()), threads, [&](int64_t v) {
        return !std::isfinite(vertices[3 * v]) || !std::isfinite(vertices[3 * v + 1]) || !std::isfinite(vertices[3 * v + 2]);
    });

    // Triangles with a repeated index have no well-defined edges or fan position: counted as degenerate above and
    // left out of the topology (a copy without them is made only when there are any).
    const TriMesh filtered = repeated > 0 ? without_repeated_index_triangles(mesh) : TriMesh{};
    const TriMesh& topology = repeated > 0 ? filtered : mesh;
    const FanAndEdgeCounts counts = count_fan_and_edge_problems(topology, build_vertex_triangles(topology, threads), threads);
    check.boundary_edges = counts.boundary_edges;
    check.non_manifold_edges = counts.non_manifold_edges;
    check.inconsistent_edges = counts.inconsistent_edges;
    check.non_manifold_vertices = counts.non_manifold_vertices;
    // A vertex used only by triangles with a repeated index still counts as referenced.
    check.unreferenced_vertices = repeated > 0 ? count_unreferenced_vertices(mesh) : counts.unreferenced_vertices;
    return check;
}

}  // namespace meniscus
