// check_mesh: the consistency report every post-processing stage is tested against (closed, 2-manifold,
// consistently oriented, no degenerate triangles, finite coordinates).
#include <algorithm>
#include <array>
#include <cmath>
#include <string>
#include <vector>

#include "mesh/adjacency.h"
#include "post/postprocess.h"

namespace meniscus {

namespace {

bool has_repeated_index(const int32_t* t) { return t[0] == t[1] || t[1] == t[2] || t[2] == t[0]; }

}  // namespace

bool triangle_has_zero_area(const float* v, const int32_t* t) {
    const float* a = v + 3 * static_cast<int64_t>(t[0]);
    const float* b = v + 3 * static_cast<int64_t>(t[1]);
    const float* c = v + 3 * static_cast<int64_t>(t[2]);
    const double e1[3] = {double(b[0]) - a[0], double(b[1]) - a[1], double(b[2]) - a[2]};
    const double e2[3] = {double(c[0]) - a[0], double(c[1]) - a[1], double(c[2]) - a[2]};
    const double n[3] = {e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2], e1[0] * e2[1] - e1[1] * e2[0]};
    return n[0] == 0.0 && n[1] == 0.0 && n[2] == 0.0;
}

namespace {

// The fan of triangles around v is one disk when its link (edge next(v) -> prev(v) of every triangle) is a
// single cycle, or a single path at a boundary: every link vertex has at most two link edges and the link graph
// is connected. A bow-tie (two fans meeting at v) has two components.
struct VertexScratch {
    std::vector<int32_t> link_vertices, degree, parent;
    std::vector<EdgeIncidence> edges;
};

int32_t find_root(std::vector<int32_t>& parent, int32_t i) {
    while (parent[i] != i) i = parent[i] = parent[parent[i]];
    return i;
}

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
    s.parent.resize(static_cast<std::size_t>(n));
    for (int32_t i = 0; i < n; ++i) s.parent[i] = i;
    int32_t components = n;
    for (int64_t k = vt.begin(v); k < vt.end(v); ++k) {
        const int32_t* t = tris + 3 * static_cast<int64_t>(vt.items[k]);
        int corner = 0;
        while (t[corner] != v) ++corner;
        const int32_t a = local(t[(corner + 1) % 3]), b = local(t[(corner + 2) % 3]);
        if (++s.degree[a] > 2 || ++s.degree[b] > 2) return false;
        const int32_t ra = find_root(s.parent, a), rb = find_root(s.parent, b);
        if (ra != rb) {
            s.parent[ra] = rb;
            --components;
        }
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

MeshCheck check_mesh(const TriMesh& mesh) {
    validate_mesh_arrays(mesh, "check_mesh");
    const int threads = 0;
    MeshCheck check;
    const int64_t nv = static_cast<int64_t>(mesh.num_vertices());
    const int64_t nt = static_cast<int64_t>(mesh.num_triangles());
    const int32_t* tris = mesh.triangles.data();

    // Triangles with a repeated index have no well-defined edges or fan position: count them as degenerate and
    // leave them out of the topology (a copy without them is made only when there are any).
    std::size_t repeated = 0, zero = 0, non_finite = 0;
#pragma omp parallel for reduction(+ : repeated, zero) schedule(static) num_threads(resolve_threads(threads))
    for (int64_t t = 0; t < nt; ++t) {
        if (has_repeated_index(tris + 3 * t)) ++repeated;
        else if (triangle_has_zero_area(mesh.vertices.data(), tris + 3 * t)) ++zero;
    }
#pragma omp parallel for reduction(+ : non_finite) schedule(static) num_threads(resolve_threads(threads))
    for (int64_t v = 0; v < nv; ++v)
        if (!std::isfinite(mesh.vertices[3 * v]) || !std::isfinite(mesh.vertices[3 * v + 1]) ||
            !std::isfinite(mesh.vertices[3 * v + 2]))
            ++non_finite;
    check.degenerate_triangles = repeated + zero;
    check.non_finite_vertices = non_finite;

    TriMesh filtered;
    const TriMesh* topo = &mesh;
    if (repeated > 0) {
        filtered.vertices = mesh.vertices;
        filtered.triangles.reserve(mesh.triangles.size());
        for (int64_t t = 0; t < nt; ++t)
            if (!has_repeated_index(tris + 3 * t)) filtered.triangles.insert(filtered.triangles.end(), tris + 3 * t, tris + 3 * t + 3);
        topo = &filtered;
    }
    const CsrList vt = build_vertex_triangles(*topo, threads);

    // One pass over the vertices: each undirected edge is examined at its smaller vertex (triangle count and
    // traversal directions), each vertex's fan is checked for being a single disk.
    constexpr int64_t kBlock = 4096;
    const int64_t blocks = (nv + kBlock - 1) / kBlock;
    std::vector<std::array<std::size_t, 5>> partial(static_cast<std::size_t>(blocks));
    parallel_for(blocks, threads, [&](int64_t b) {
        VertexScratch s;
        std::array<std::size_t, 5> c{};  // boundary, non-manifold edges, inconsistent, non-manifold vertices, unreferenced
        for (int64_t v = b * kBlock; v < std::min(nv, (b + 1) * kBlock); ++v) {
            if (vt.size(v) == 0) {
                ++c[4];
                continue;
            }
            if (!fan_is_single_disk(*topo, vt, static_cast<int32_t>(v), s)) ++c[3];
            upper_edge_incidences(*topo, vt, static_cast<int32_t>(v), s.edges);
            for (std::size_t i = 0; i < s.edges.size();) {
                std::size_t j = i;
                int32_t direction = 0;
                for (; j < s.edges.size() && s.edges[j].other == s.edges[i].other; ++j) direction += s.edges[j].direction;
                const std::size_t count = j - i;
                if (count == 1) ++c[0];
                else if (count > 2) ++c[1];
                else if (direction != 0) ++c[2];  // consistent: one triangle runs v -> u, the other u -> v
                i = j;
            }
        }
        partial[b] = c;
    });
    std::size_t unreferenced = 0;
    for (const auto& c : partial) {
        check.boundary_edges += c[0];
        check.non_manifold_edges += c[1];
        check.inconsistent_edges += c[2];
        check.non_manifold_vertices += c[3];
        unreferenced += c[4];
    }
    if (repeated > 0) {  // a vertex used only by triangles with a repeated index still counts as referenced
        std::vector<uint8_t> used(static_cast<std::size_t>(nv), 0);
        for (std::size_t i = 0; i < mesh.triangles.size(); ++i) used[tris[i]] = 1;
        unreferenced = 0;
        for (int64_t v = 0; v < nv; ++v) unreferenced += used[v] ? 0 : 1;
    }
    check.unreferenced_vertices = unreferenced;
    return check;
}

}  // namespace meniscus
