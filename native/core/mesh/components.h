// Connected components of a triangle mesh (by shared vertices) and sums per component, the enclosed volume above
// all. Used by volume restoration (post/volume.h) and the quality report (analysis/quality.h).
#pragma once
#include <algorithm>
#include <array>
#include <cstdint>
#include <vector>

#include "base/parallel.h"
#include "base/uninitialized_vector.h"
#include "mesh/geometry.h"
#include "mesh/mesh.h"

namespace meniscus {

// A label per vertex (0 .. count-1, numbered in the order of each component's smallest vertex index, so
// deterministic) and their count. Unreferenced vertices get their own labels.
std::vector<int32_t> component_labels(const TriMesh& mesh, int32_t* count, int threads = 1);

// Per-component sums of W values per triangle, value(t) -> std::array<double, W>, over the triangles t, a triangle
// counting for the component of its first corner; W sums per component, interleaved (component c's k-th at W c + k).
// Triangles go in fixed blocks (independent of the thread count), each block sums into its own row in triangle
// order and the rows are added in block order, so the result is the same bits for any thread count (and each of the
// W sums has the bits it would have alone). With very many components the rows would cost too much memory: then
// fewer, longer blocks.
template <int W, class Value>
std::vector<double> sums_per_component(const TriMesh& mesh, const std::vector<int32_t>& labels, int32_t count, int threads,
                                       const Value& value) {
    constexpr int64_t kBlock = int64_t(1) << 16;
    constexpr int64_t kMaxPartialSums = int64_t(1) << 22;  // 32 MiB of rows
    const int64_t triangles = static_cast<int64_t>(mesh.num_triangles());
    const int64_t width = int64_t{W} * count;
    auto add = [&](int64_t t, double* row) {
        const int64_t first = W * static_cast<int64_t>(labels[mesh.triangles[3 * static_cast<std::size_t>(t)]]);
        const auto values = value(t);
        for (int k = 0; k < W; ++k) row[first + k] += values[k];
    };
    int64_t block = kBlock;
    int64_t blocks = (triangles + block - 1) / block;
    if (blocks * width > kMaxPartialSums) {
        // Many components (droplets of a large frame): fewer, longer blocks keep the rows within the cap, instead of
        // one serial pass (which was several serial passes over every triangle per volume correction at 4 M
        // particles). The blocks follow from the mesh alone, so the sums have the same bits at any thread count.
        const int64_t most = kMaxPartialSums / std::max<int64_t>(width, 1);
        block = most > 1 ? (triangles + most - 1) / most : triangles;
        blocks = (triangles + block - 1) / block;
    }
    std::vector<double> total(static_cast<std::size_t>(width), 0.0);
    if (blocks <= 1) {
        for (int64_t t = 0; t < triangles; ++t) add(t, total.data());
        return total;
    }
    // A row per block, zeroed and filled by the thread that takes the block, then every component's rows added in
    // block order by components in parallel: neither the rows' ~10 MB (thousands of droplets) nor their sum is a serial
    // pass (four per volume correction).
    UninitializedVector<double> rows(static_cast<std::size_t>(blocks * width));
    parallel_for(blocks, threads, [&](int64_t b) {
        double* row = rows.data() + b * width;
        std::fill(row, row + width, 0.0);
        for (int64_t t = b * block, end = std::min(triangles, (b + 1) * block); t < end; ++t) add(t, row);
    });
    parallel_blocks(width, width > 4096 ? threads : 1, 4096, [&](int64_t begin, int64_t end) {
        for (int64_t b = 0; b < blocks; ++b)
            for (int64_t c = begin; c < end; ++c) total[c] += rows[b * width + c];
    });
    return total;
}

// One value per triangle: sums_per_component with W = 1.
template <class Value>
std::vector<double> sum_per_component(const TriMesh& mesh, const std::vector<int32_t>& labels, int32_t count, int threads,
                                      const Value& value) {
    return sums_per_component<1>(mesh, labels, count, threads, [&](int64_t t) { return std::array<double, 1>{value(t)}; });
}

// Each component's smallest vertex (the origin its volume is measured from).
std::vector<int32_t> component_smallest_vertices(const std::vector<int32_t>& labels, int32_t count, int threads);

// Triangle tri's term of its component's signed volume, measured from the component's smallest vertex `origin`.
inline double component_volume_term(const float* vertices, const int32_t* tri, int32_t origin) {
    const Vec3d o = vertex_position(vertices, origin);
    return tetrahedron_volume(vertex_position(vertices, tri[0]) - o, vertex_position(vertices, tri[1]) - o, vertex_position(vertices, tri[2]) - o);
}

// Signed enclosed volume per component (divergence theorem, in double), measured from each component's smallest
// vertex so that the sum stays accurate far from the origin; positive for a body, negative for a bubble.
std::vector<double> component_volumes(const TriMesh& mesh, const std::vector<int32_t>& labels, int32_t count, int threads = 1);

}  // namespace meniscus
