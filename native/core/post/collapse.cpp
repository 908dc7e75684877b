#include "post/collapse.h"

#include "base/compaction.h"
#include "base/parallel.h"
#include "base/parallel_move.h"

namespace meniscus {

namespace {

constexpr int64_t kBlock = 4096;
// Most removed vertices whose kept runs compact_into moves in place (one parallel move per run).
constexpr int64_t kMostRunsMovedInPlace = 1024;

// Drops the items listed in `gone` (ascending) from values, 3 per item, in place: the kept items between two dropped
// ones move down by as many items as were dropped before them; the runs in ascending order, as a serial sweep moves
// them, each run in parallel (a few items dropped of millions: the runs are long).
template <class T>
void drop_items_in_place(std::vector<T>& values, const std::vector<int32_t>& gone, int threads) {
    const int64_t n = static_cast<int64_t>(values.size() / 3);
    for (std::size_t i = 0; i < gone.size(); ++i) {
        const int64_t first = gone[i] + 1, last = i + 1 < gone.size() ? gone[i + 1] : n;
        const int64_t before = static_cast<int64_t>(i) + 1;
        move_in_parallel(values.data(), 3 * first, 3 * (first - before), 3 * (last - first), threads);
    }
    values.resize(3 * static_cast<std::size_t>(n - static_cast<int64_t>(gone.size())));
}

}  // namespace

MeshAdjacency working_adjacency(std::vector<int32_t>& triangles, std::vector<float>& positions, int threads) {
    TriMesh view;  // borrows the arrays for the build and hands them back
    view.vertices.swap(positions);
    view.triangles.swap(triangles);
    MeshAdjacency adjacency = build_adjacency(view, threads);
    positions.swap(view.vertices);
    triangles.swap(view.triangles);
    return adjacency;
}

void drop_deleted_triangles(std::vector<int32_t>& triangles, const UninitializedVector<uint8_t>& deleted, int threads) {
    const int64_t nt = static_cast<int64_t>(deleted.size());
    drop_items_in_place(triangles, kept_indices(nt, threads, [&](int64_t t) { return deleted[t] != 0; }), threads);
}

UninitializedVector<int32_t> compact_into(TriMesh& mesh, std::vector<int32_t>& triangles, std::vector<float>& positions,
                                          const std::vector<uint8_t>& removed, const UninitializedVector<int32_t>* group_next, int threads) {
    const int64_t nv = static_cast<int64_t>(removed.size());
    UninitializedVector<int32_t> new_index(static_cast<std::size_t>(nv));  // every entry numbered below
    number_kept(nv, threads, [&](int64_t v) { return !removed[v]; }, new_index.data());
    const std::vector<int32_t> survivors = kept_indices(nv, threads, [&](int64_t v) { return !removed[v]; });
    const int64_t ns = static_cast<int64_t>(survivors.size());
    const int64_t indices = static_cast<int64_t>(triangles.size()), block = 16 * kBlock;
    std::vector<float> vertices;
    if (nv - ns <= kMostRunsMovedInPlace) {
        // Few removed (decimation removes a few vertices per barnacle): the kept runs between them move down in place,
        // as drop_deleted_triangles moves triangles; a new array would be zero-filled on one thread (~10 ms at 1 M
        // particles, the longest serial step left in decimation at 16 threads).
        parallel_blocks(indices, threads, block, [&](int64_t begin, int64_t end) {
            for (int64_t i = begin; i < end; ++i) triangles[i] = new_index[triangles[i]];
        });
        drop_items_in_place(positions, kept_indices(nv, threads, [&](int64_t v) { return removed[v] != 0; }), threads);
        vertices.swap(positions);
    } else {
        // The new vertex array (a std::vector: zero-filled on one thread) is made by one thread while the others
        // renumber the triangles.
        parallel_for((indices + block - 1) / block + 1, threads, [&](int64_t item) {
            if (item == 0) {
                vertices.resize(3 * static_cast<std::size_t>(ns));
                return;
            }
            for (int64_t i = (item - 1) * block, end = std::min(indices, item * block); i < end; ++i) triangles[i] = new_index[triangles[i]];
        });
        parallel_blocks(ns, threads, kBlock, [&](int64_t begin, int64_t end) {
            for (int64_t i = begin; i < end; ++i)
                for (int k = 0; k < 3; ++k) vertices[3 * i + k] = positions[3 * static_cast<int64_t>(survivors[i]) + k];
        });
    }
    auto gather = [&](std::vector<float>& values, int components, bool renormalise) {
        std::vector<float> out(static_cast<std::size_t>(ns) * components);
        parallel_blocks(ns, threads, kBlock, [&](int64_t begin, int64_t end) {
            std::vector<double> sum(static_cast<std::size_t>(components));
            for (int64_t i = begin; i < end; ++i) {
                const int64_t v = survivors[i];
                float* dst = out.data() + i * components;
                const float* own = values.data() + v * components;
                if (!group_next || (*group_next)[v] == -1) {
                    std::copy(own, own + components, dst);
                    continue;
                }
                std::fill(sum.begin(), sum.end(), 0.0);
                int64_t count = 0;
                for (int32_t u = static_cast<int32_t>(v); u != -1; u = (*group_next)[u], ++count)
                    for (int k = 0; k < components; ++k) sum[k] += values[static_cast<int64_t>(u) * components + k];
                double length = 0.0;
                for (int k = 0; k < components; ++k) length += sum[k] * sum[k];
                if (renormalise) {
                    length = std::sqrt(length);
                    if (!(length > 0.0) || !std::isfinite(length)) {
                        std::copy(own, own + components, dst);
                        continue;
                    }
                    for (int k = 0; k < components; ++k) dst[k] = static_cast<float>(sum[k] / length);
                } else {
                    for (int k = 0; k < components; ++k) dst[k] = static_cast<float>(sum[k] / double(count));
                }
            }
        });
        values.swap(out);
    };
    if (!mesh.normals.empty()) gather(mesh.normals, 3, true);
    for (Attribute& a : mesh.attributes) gather(a.values, a.components, false);
    mesh.vertices.swap(vertices);
    mesh.triangles.swap(triangles);
    return new_index;
}

}  // namespace meniscus
