// Connected components of a triangle mesh (by shared vertices) and sums per component, the enclosed volume above
// all. Used by volume restoration (post/volume.h) and the quality report (analysis/quality.h).
#pragma once
#include <algorithm>
#include <cstdint>
#include <vector>

#include "base/parallel.h"
#include "mesh/mesh.h"

namespace meniscus {

// A label per vertex (0 .. count-1, numbered in the order of each component's smallest vertex index, so
// deterministic) and their count. Unreferenced vertices get their own labels.
std::vector<int32_t> component_labels(const TriMesh& mesh, int32_t* count, int threads = 1);

// Per-component sums of value(t) over the triangles t, a triangle counting for the component of its first corner.
// Triangles go in fixed blocks (independent of the thread count), each block sums into its own row in triangle
// order and the rows are added in block order, so the result is the same bits for any thread count. With very many
// components the rows would cost too much memory: then one sequential pass (also in triangle order).
template <class Value>
std::vector<double> sum_per_component(const TriMesh& mesh, const std::vector<int32_t>& labels, int32_t count, int threads,
                                      const Value& value) {
    constexpr int64_t kBlock = int64_t(1) << 16;
    constexpr int64_t kMaxPartialSums = int64_t(1) << 22;  // 32 MiB of rows
    const int64_t triangles = static_cast<int64_t>(mesh.num_triangles());
    auto component = [&](int64_t t) { return labels[mesh.triangles[3 * static_cast<std::size_t>(t)]]; };
    const std::vector<double> zero(static_cast<std::size_t>(count), 0.0);
    int64_t block = kBlock;
    int64_t blocks = (triangles + block - 1) / block;
    if (blocks * count > kMaxPartialSums) {
        // Many components (droplets of a large frame): fewer, longer blocks keep the rows within the cap, instead of
        // one serial pass (which was several serial passes over every triangle per volume correction at 4 M
        // particles). The blocks follow from the mesh alone, so the sums have the same bits at any thread count.
        const int64_t most = kMaxPartialSums / std::max<int64_t>(count, 1);
        block = most > 1 ? (triangles + most - 1) / most : triangles;
        blocks = (triangles + block - 1) / block;
    }
    if (blocks <= 1) {
        std::vector<double> total = zero;
        for (int64_t t = 0; t < triangles; ++t) total[component(t)] += value(t);
        return total;
    }
    return ordered_block_reduce(
        triangles, threads, block, zero,
        [&](int64_t begin, int64_t end, std::vector<double>& row) {
            for (int64_t t = begin; t < end; ++t) row[component(t)] += value(t);
        },
        [](std::vector<double>& total, const std::vector<double>& row) {
            for (std::size_t c = 0; c < total.size(); ++c) total[c] += row[c];
        });
}

// Signed enclosed volume per component (divergence theorem, in double), measured from each component's smallest
// vertex so that the sum stays accurate far from the origin; positive for a body, negative for a bubble.
std::vector<double> component_volumes(const TriMesh& mesh, const std::vector<int32_t>& labels, int32_t count, int threads = 1);

}  // namespace meniscus
