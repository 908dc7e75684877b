#include "mesh/components.h"

#include <atomic>
#include <limits>

#include "base/compaction.h"
#include "base/concurrent_disjoint_sets.h"
#include "base/parallel.h"
#include "mesh/geometry.h"

namespace meniscus {

std::vector<int32_t> component_labels(const TriMesh& mesh, int32_t* count, int threads) {
    // Unions in parallel: every component ends rooted at its smallest vertex (base/concurrent_disjoint_sets.h), so
    // numbering the roots in vertex order numbers the components as a serial pass meeting them in that order would.
    const int64_t n = static_cast<int64_t>(mesh.num_vertices());
    ConcurrentDisjointSets components(static_cast<std::size_t>(n), threads);
    parallel_blocks(static_cast<int64_t>(mesh.num_triangles()), threads, int64_t{1} << 14, [&](int64_t begin, int64_t end) {
        for (int64_t t = begin; t < end; ++t) {
            const int32_t* tri = &mesh.triangles[3 * t];
            components.unite(tri[0], tri[1]);
            components.unite(tri[0], tri[2]);
        }
    });
    std::vector<int32_t> root(static_cast<std::size_t>(n));
    parallel_blocks(n, threads, int64_t{1} << 14, [&](int64_t begin, int64_t end) {
        for (int64_t v = begin; v < end; ++v) root[v] = components.find(static_cast<int32_t>(v));
    });
    std::vector<int32_t> labels(static_cast<std::size_t>(n));
    const int64_t next = number_kept(n, threads, [&](int64_t v) { return root[v] == v; }, labels.data());
    parallel_blocks(n, threads, int64_t{1} << 14, [&](int64_t begin, int64_t end) {
        for (int64_t v = begin; v < end; ++v)
            if (root[v] != v) labels[v] = labels[root[v]];  // a root's own label is set above
    });
    if (count) *count = static_cast<int32_t>(next);
    return labels;
}

std::vector<int32_t> component_smallest_vertices(const std::vector<int32_t>& labels, int32_t count, int threads) {
    // By an atomic minimum: the same vertex whatever the order.
    std::vector<std::atomic<int32_t>> smallest(static_cast<std::size_t>(count));
    for (auto& first : smallest) first.store(std::numeric_limits<int32_t>::max(), std::memory_order_relaxed);
    parallel_blocks(static_cast<int64_t>(labels.size()), threads, int64_t{1} << 14, [&](int64_t begin, int64_t end) {
        for (int64_t v = begin; v < end; ++v) {
            std::atomic<int32_t>& first = smallest[static_cast<std::size_t>(labels[v])];
            int32_t seen = first.load(std::memory_order_relaxed);
            while (v < seen && !first.compare_exchange_weak(seen, static_cast<int32_t>(v), std::memory_order_relaxed)) {
            }
        }
    });
    std::vector<int32_t> reference(static_cast<std::size_t>(count));
    for (std::size_t c = 0; c < reference.size(); ++c) reference[c] = smallest[c].load(std::memory_order_relaxed);
    return reference;
}

std::vector<double> component_volumes(const TriMesh& mesh, const std::vector<int32_t>& labels, int32_t count, int threads) {
    const std::vector<int32_t> reference = component_smallest_vertices(labels, count, threads);
    const float* vertices = mesh.vertices.data();
    const int32_t* tris = mesh.triangles.data();
    return sum_per_component(mesh, labels, count, threads, [&](int64_t t) {
        const int32_t* tri = tris + 3 * t;
        return component_volume_term(vertices, tri, reference[labels[tri[0]]]);
    });
}

}  // namespace meniscus
