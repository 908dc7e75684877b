#include "analysis/scale_metrics.h"

#include <algorithm>
#include <cmath>

#include "base/parallel.h"
#include "mesh/adjacency.h"
#include "post/heat_smoothing.h"
#include "post/smoothing.h"
#include "mesh/components.h"

namespace meniscus {

namespace {

constexpr int64_t kSumBlock = 8192;

double mean_distance(const TriMesh& mesh, const MeshAdjacency& adjacency, const std::vector<float>& other, int threads) {
    const int64_t nv = static_cast<int64_t>(mesh.num_vertices());
    const double used = ordered_block_sum(nv, threads, kSumBlock, [&](int64_t v) { return adjacency.valence(v) > 0 ? 1.0 : 0.0; });
    const double total = ordered_block_sum(nv, threads, kSumBlock, [&](int64_t v) {
        if (adjacency.valence(v) == 0) return 0.0;
        double d2 = 0.0;
        for (int k = 0; k < 3; ++k) {
            const double d = double(other[3 * v + k]) - mesh.vertices[3 * v + k];
            d2 += d * d;
        }
        const double d = std::sqrt(d2);
        return std::isfinite(d) ? d : 0.0;
    });
    return used > 0.0 ? total / used : 0.0;
}

}  // namespace

double taubin_distance(const TriMesh& mesh, const MeshAdjacency& adjacency, int passes, int threads) {
    threads = resolve_threads(threads);
    std::vector<float> a(mesh.vertices), b(mesh.vertices.size());
    for (int pass = 0; pass < passes; ++pass) {
        umbrella_step(adjacency.vertex_neighbours, a.data(), b.data(), nullptr, 0.5, threads);
        umbrella_step(adjacency.vertex_neighbours, b.data(), a.data(), nullptr, -0.53, threads);
    }
    return mean_distance(mesh, adjacency, a, threads);
}

int hfl_passes(double length, double raw_mean_edge) {
    if (!(length > 0.0) || !(raw_mean_edge > 0.0)) return 0;
    return static_cast<int>(std::lround(std::min(1.36 * (length / raw_mean_edge) * (length / raw_mean_edge), 1.0e6)));
}

double heat_distance(const TriMesh& mesh, const MeshAdjacency& adjacency, double length, int threads) {
    threads = resolve_threads(threads);
    const double edge = rms_edge_length(mesh, adjacency, threads);
    if (!(edge > 0.0) || !(length > 0.0)) return 0.0;
    // 2 H(t) - H(2 t): the heat kernel's response 1 - t k^2 + ... made flat to second order, so that curved shapes
    // (a tube, a drop) are not measured by the shrinkage a plain heat flow gives them; high frequencies still go.
    const double n = std::min((length / edge) * (length / edge), 1.0e5);
    std::vector<float> once(mesh.vertices), twice(mesh.vertices);
    heat_filter(once, 3, adjacency, {}, n, kPositionTolerance, threads);
    heat_filter(twice, 3, adjacency, {}, 2.0 * n, kPositionTolerance, threads);
    for (std::size_t i = 0; i < once.size(); ++i) once[i] = 2.0f * once[i] - twice[i];
    return mean_distance(mesh, adjacency, once, threads);
}

double mean_edge_length(const TriMesh& mesh, const MeshAdjacency& adjacency, int threads) {
    const CsrList& nb = adjacency.vertex_neighbours;
    const int64_t nv = static_cast<int64_t>(nb.rows());
    auto edges_from = [&](int64_t v, bool length) {
        double s = 0.0;
        for (int64_t k = nb.begin(v); k < nb.end(v); ++k) {
            const int64_t j = nb.items[k];
            if (j <= v) continue;
            if (!length) {
                s += 1.0;
                continue;
            }
            double d2 = 0.0;
            for (int c = 0; c < 3; ++c) {
                const double d = double(mesh.vertices[3 * j + c]) - mesh.vertices[3 * v + c];
                d2 += d * d;
            }
            s += std::sqrt(d2);
        }
        return s;
    };
    const double count = ordered_block_sum(nv, threads, kSumBlock, [&](int64_t v) { return edges_from(v, false); });
    const double total = ordered_block_sum(nv, threads, kSumBlock, [&](int64_t v) { return edges_from(v, true); });
    return count > 0.0 ? total / count : 0.0;
}

ComponentSummary component_summary(const TriMesh& mesh) {
    int32_t count = 0;
    const std::vector<int32_t> labels = component_labels(mesh, &count);
    std::vector<int32_t> slot(static_cast<std::size_t>(count), -1);
    ComponentSummary out;
    std::vector<double> mean, mean_count;
    std::vector<int32_t> reference;
    for (std::size_t t = 0; t < mesh.num_triangles(); ++t) {
        const int32_t* tri = &mesh.triangles[3 * t];
        const int32_t label = labels[tri[0]];
        if (slot[label] < 0) {
            slot[label] = static_cast<int32_t>(out.volume.size());
            out.volume.push_back(0.0);
            out.centroid.insert(out.centroid.end(), {0.0, 0.0, 0.0});
            mean.insert(mean.end(), {0.0, 0.0, 0.0});
            mean_count.push_back(0.0);
            reference.push_back(tri[0]);
        }
        const int32_t s = slot[label];
        const float* o = &mesh.vertices[3 * static_cast<std::size_t>(reference[s])];
        double p[3][3];
        for (int i = 0; i < 3; ++i)
            for (int k = 0; k < 3; ++k) p[i][k] = double(mesh.vertices[3 * static_cast<std::size_t>(tri[i]) + k]) - o[k];
        const double vol = (p[0][0] * (p[1][1] * p[2][2] - p[1][2] * p[2][1]) - p[0][1] * (p[1][0] * p[2][2] - p[1][2] * p[2][0]) +
                            p[0][2] * (p[1][0] * p[2][1] - p[1][1] * p[2][0])) / 6.0;
        out.volume[s] += vol;
        for (int k = 0; k < 3; ++k) {
            out.centroid[3 * s + k] += vol * (p[0][k] + p[1][k] + p[2][k]) / 4.0;
            mean[3 * s + k] += (p[0][k] + p[1][k] + p[2][k]) / 3.0;
        }
        mean_count[s] += 1.0;
    }
    for (std::size_t s = 0; s < out.volume.size(); ++s) {
        const float* o = &mesh.vertices[3 * static_cast<std::size_t>(reference[s])];
        for (int k = 0; k < 3; ++k) {
            const double fallback = mean[3 * s + k] / mean_count[s];
            const double c = std::fabs(out.volume[s]) > 0.0 ? out.centroid[3 * s + k] / out.volume[s] : fallback;
            out.centroid[3 * s + k] = (std::isfinite(c) ? c : fallback) + o[k];
        }
    }
    return out;
}

}  // namespace meniscus
