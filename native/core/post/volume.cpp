#include "post/volume.h"

#include <algorithm>
#include <cmath>
#include <numeric>

#include "mesh/adjacency.h"
#include "base/parallel.h"
#include "post/postprocess.h"

namespace meniscus {

namespace {

int32_t find_root(std::vector<int32_t>& parent, int32_t v) {
    while (parent[v] != v) {
        parent[v] = parent[parent[v]];
        v = parent[v];
    }
    return v;
}

// Per-component sums of value(t) over the triangles t of mesh, a triangle counting for the component of its first
// corner. Triangles go in fixed blocks (independent of the thread count), each block sums into its own row in
// triangle order and the rows are added in block order, so the result is the same bits for any thread count. With
// very many components the rows would cost too much memory: then one sequential pass (also in triangle order).
constexpr int64_t kSumBlock = int64_t(1) << 16;
constexpr int64_t kMaxSumCells = int64_t(1) << 22;  // 32 MiB of partial sums

template <class Value>
std::vector<double> sum_per_component(const TriMesh& mesh, const std::vector<int32_t>& labels, int32_t count, int threads,
                                      const Value& value) {
    const int64_t triangles = static_cast<int64_t>(mesh.num_triangles());
    auto component = [&](int64_t t) { return labels[mesh.triangles[3 * static_cast<std::size_t>(t)]]; };
    std::vector<double> total(static_cast<std::size_t>(count), 0.0);
    const int64_t blocks = (triangles + kSumBlock - 1) / kSumBlock;
    if (blocks <= 1 || blocks * count > kMaxSumCells) {
        for (int64_t t = 0; t < triangles; ++t) total[component(t)] += value(t);
        return total;
    }
    std::vector<double> partial(static_cast<std::size_t>(blocks * count), 0.0);
    parallel_for(blocks, threads, [&](int64_t b) {
        double* row = partial.data() + b * count;
        for (int64_t t = b * kSumBlock; t < std::min(triangles, (b + 1) * kSumBlock); ++t) row[component(t)] += value(t);
    });
    for (int64_t b = 0; b < blocks; ++b)
        for (int32_t c = 0; c < count; ++c) total[c] += partial[b * count + c];
    return total;
}

}  // namespace

std::vector<int32_t> component_labels(const TriMesh& mesh, int32_t* count) {
    const std::size_t n = mesh.num_vertices();
    std::vector<int32_t> parent(n);
    std::iota(parent.begin(), parent.end(), 0);
    for (std::size_t t = 0; t < mesh.num_triangles(); ++t) {
        const int32_t* tri = &mesh.triangles[3 * t];
        for (int k = 1; k < 3; ++k) {
            const int32_t a = find_root(parent, tri[0]), b = find_root(parent, tri[k]);
            if (a != b) parent[std::max(a, b)] = std::min(a, b);  // the smaller index is the root: deterministic
        }
    }
    std::vector<int32_t> labels(n, -1);
    int32_t next = 0;
    for (std::size_t v = 0; v < n; ++v) {
        const int32_t root = find_root(parent, static_cast<int32_t>(v));
        if (labels[root] < 0) labels[root] = next++;
        labels[v] = labels[root];
    }
    if (count) *count = next;
    return labels;
}

std::vector<double> component_volumes(const TriMesh& mesh, const std::vector<int32_t>& labels, int32_t count, int threads) {
    // Relative to each component's first vertex: keeps the sum accurate far from the origin.
    std::vector<int32_t> reference(static_cast<std::size_t>(count), -1);
    for (std::size_t v = 0; v < labels.size(); ++v)
        if (reference[labels[v]] < 0) reference[labels[v]] = static_cast<int32_t>(v);
    const int32_t* tris = mesh.triangles.data();
    return sum_per_component(mesh, labels, count, threads, [&](int64_t t) {
        const int32_t* tri = tris + 3 * t;
        const float* o = &mesh.vertices[3 * static_cast<std::size_t>(reference[labels[tri[0]]])];
        double p[3][3];
        for (int i = 0; i < 3; ++i)
            for (int k = 0; k < 3; ++k) p[i][k] = double(mesh.vertices[3 * static_cast<std::size_t>(tri[i]) + k]) - double(o[k]);
        return (p[0][0] * (p[1][1] * p[2][2] - p[1][2] * p[2][1]) - p[0][1] * (p[1][0] * p[2][2] - p[1][2] * p[2][0]) +
                p[0][2] * (p[1][0] * p[2][1] - p[1][1] * p[2][0])) / 6.0;
    });
}

void restore_component_volumes(TriMesh& mesh, const MeshAdjacency& adjacency, const std::vector<int32_t>& labels,
                               const std::vector<double>& target, const std::vector<float>& amount, double max_offset,
                               int normal_iterations, int threads) {
    // Smoothed normals: offsets along raw vertex normals would print the triangulation's noise back in. The offsets
    // are small against the features, so the directions computed once serve both Newton steps. Computed before
    // anything else, since the caller takes them as the mesh's normals even when there is nothing to restore.
    compute_area_weighted_normals(mesh, adjacency, threads);
    smooth_normals(mesh, adjacency, normal_iterations, threads);
    const int32_t count = static_cast<int32_t>(target.size());
    if (count == 0 || mesh.num_triangles() == 0) return;
    std::vector<double> applied(static_cast<std::size_t>(count), 0.0);
    // Volume is close to linear in the offset for offsets small against the feature size: two Newton steps
    // bring it within a small fraction of a percent.
    for (int step = 0; step < 2; ++step) {
        const std::vector<double> volume = component_volumes(mesh, labels, count, threads);
        // After the first step the volume is usually within a few millionths: then a second step changes nothing
        // worth its two passes over the mesh.
        bool converged = step > 0;
        for (int32_t c = 0; c < count && converged; ++c)
            converged = std::fabs(target[c] - volume[c]) <= 1e-5 * std::fabs(target[c]);
        if (converged) break;
        // d volume / d s = sum_i amount_i * A_i, with A_i a third of the incident triangle areas.
        const int32_t* tris = mesh.triangles.data();
        const std::vector<double> rate = sum_per_component(mesh, labels, count, threads, [&](int64_t t) {
            const int32_t* tri = tris + 3 * t;
            const float* a = &mesh.vertices[3 * static_cast<std::size_t>(tri[0])];
            const float* b = &mesh.vertices[3 * static_cast<std::size_t>(tri[1])];
            const float* c = &mesh.vertices[3 * static_cast<std::size_t>(tri[2])];
            const double u[3] = {double(b[0]) - a[0], double(b[1]) - a[1], double(b[2]) - a[2]};
            const double w[3] = {double(c[0]) - a[0], double(c[1]) - a[1], double(c[2]) - a[2]};
            const double n[3] = {u[1] * w[2] - u[2] * w[1], u[2] * w[0] - u[0] * w[2], u[0] * w[1] - u[1] * w[0]};
            const double third_area = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]) / 6.0;
            double sum = 0.0;
            for (int i = 0; i < 3; ++i) sum += third_area * (amount.empty() ? 1.0 : double(amount[tri[i]]));
            return sum;
        });
        std::vector<double> offset(static_cast<std::size_t>(count), 0.0);
        bool any = false;
        for (int32_t c = 0; c < count; ++c) {
            if (rate[c] <= 0.0) continue;
            double s = (target[c] - volume[c]) / rate[c];
            // Cap the accumulated offset: a component that smoothing collapsed is not blown back up from nothing.
            s = std::min(std::max(applied[c] + s, -max_offset), max_offset) - applied[c];
            applied[c] += s;
            offset[c] = s;
            any = any || s != 0.0;
        }
        if (!any) break;
        parallel_blocks(static_cast<int64_t>(mesh.num_vertices()), threads, kSumBlock, [&](int64_t begin, int64_t end) {
            for (int64_t v = begin; v < end; ++v) {
                const double s = offset[labels[v]] * (amount.empty() ? 1.0 : double(amount[v]));
                for (int k = 0; k < 3; ++k)
                    mesh.vertices[3 * v + k] = static_cast<float>(mesh.vertices[3 * v + k] + s * mesh.normals[3 * v + k]);
            }
        });
    }
}

std::size_t revert_collapsed_components(TriMesh& mesh, const std::vector<float>& before, const std::vector<int32_t>& labels,
                                        int32_t count, const std::vector<double>& volumes_before, int threads) {
    std::vector<uint8_t> collapsed(static_cast<std::size_t>(count), 0);
    const int64_t nt = static_cast<int64_t>(mesh.num_triangles());
    std::vector<uint8_t> zero_area(static_cast<std::size_t>(nt), 0);
    parallel_blocks(nt, threads, kSumBlock, [&](int64_t begin, int64_t end) {
        for (int64_t t = begin; t < end; ++t) zero_area[t] = triangle_has_zero_area(mesh.vertices.data(), &mesh.triangles[3 * t]);
    });
    for (int64_t t = 0; t < nt; ++t)
        if (zero_area[t]) collapsed[labels[mesh.triangles[3 * t]]] = 1;
    const std::vector<double> volumes = component_volumes(mesh, labels, count, threads);
    for (int32_t c = 0; c < count; ++c)
        if (volumes_before[c] != 0.0 && volumes[c] * volumes_before[c] <= 0.0) collapsed[c] = 1;  // turned inside out
    std::size_t reverted = 0;
    for (int32_t c = 0; c < count; ++c) reverted += collapsed[c];
    if (reverted == 0) return 0;
    for (std::size_t v = 0; v < mesh.num_vertices(); ++v)
        if (collapsed[labels[v]])
            for (int k = 0; k < 3; ++k) mesh.vertices[3 * v + k] = before[3 * v + k];
    return reverted;
}

}  // namespace meniscus
