#include "mesh/components.h"

#include "base/disjoint_sets.h"
#include "mesh/geometry.h"

namespace meniscus {

std::vector<int32_t> component_labels(const TriMesh& mesh, int32_t* count) {
    const std::size_t n = mesh.num_vertices();
    DisjointSets components(n);
    for (std::size_t t = 0; t < mesh.num_triangles(); ++t) {
        const int32_t* tri = &mesh.triangles[3 * t];
        components.unite(tri[0], tri[1]);
        components.unite(tri[0], tri[2]);
    }
    std::vector<int32_t> labels(n, -1);
    int32_t next = 0;
    for (std::size_t v = 0; v < n; ++v) {
        const int32_t root = components.find(static_cast<int32_t>(v));
        if (labels[root] < 0) labels[root] = next++;
        labels[v] = labels[root];
    }
    if (count) *count = next;
    return labels;
}

std::vector<double> component_volumes(const TriMesh& mesh, const std::vector<int32_t>& labels, int32_t count, int threads) {
    std::vector<int32_t> reference(static_cast<std::size_t>(count), -1);
    for (std::size_t v = 0; v < labels.size(); ++v)
        if (reference[labels[v]] < 0) reference[labels[v]] = static_cast<int32_t>(v);
    const float* vertices = mesh.vertices.data();
    const int32_t* tris = mesh.triangles.data();
    return sum_per_component(mesh, labels, count, threads, [&](int64_t t) {
        const int32_t* tri = tris + 3 * t;
        const Vec3d origin = vertex_position(vertices, reference[labels[tri[0]]]);
        return tetrahedron_volume(vertex_position(vertices, tri[0]) - origin, vertex_position(vertices, tri[1]) - origin,
                                  vertex_position(vertices, tri[2]) - origin);
    });
}

}  // namespace meniscus
