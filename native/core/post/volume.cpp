#include "post/volume.h"

#include <algorithm>
#include <array>
#include <cmath>

#include "base/parallel.h"
#include "mesh/components.h"
#include "mesh/geometry.h"
#include "mesh/topology.h"

namespace meniscus {

namespace {

constexpr int64_t kVertexBlock = int64_t(1) << 16;

// Per component, interleaved: its signed volume (component_volumes' bits) and d volume / d s, the rate at which an
// offset s * amount_i along the normals changes it: the sum of amount_i * A_i over its vertices, A_i a third of the
// incident triangles' areas. One pass over the triangles for both (they were two per Newton step).
std::vector<double> volumes_and_rates(const TriMesh& mesh, const std::vector<int32_t>& labels, int32_t count,
                                      const std::vector<int32_t>& origin, const std::vector<float>& amount, int threads) {
    const float* vertices = mesh.vertices.data();
    const int32_t* tris = mesh.triangles.data();
    return sums_per_component<2>(mesh, labels, count, threads, [&](int64_t t) {
        const int32_t* tri = tris + 3 * t;
        const double third_area = length(triangle_cross(vertices, tri)) / 6.0;
        double rate = 0.0;
        for (int i = 0; i < 3; ++i) rate += third_area * (amount.empty() ? 1.0 : double(amount[tri[i]]));
        return std::array<double, 2>{component_volume_term(vertices, tri, origin[labels[tri[0]]]), rate};
    });
}

// vertex v += offset[its component] * amount_v * normal_v
void move_along_normals(TriMesh& mesh, const std::vector<int32_t>& labels, const std::vector<double>& offset,
                        const std::vector<float>& amount, const std::vector<float>& normals, int threads) {
    parallel_blocks(static_cast<int64_t>(mesh.num_vertices()), threads, kVertexBlock, [&](int64_t begin, int64_t end) {
        for (int64_t v = begin; v < end; ++v) {
            const double s = offset[labels[v]] * (amount.empty() ? 1.0 : double(amount[v]));
            for (int k = 0; k < 3; ++k) mesh.vertices[3 * v + k] = static_cast<float>(mesh.vertices[3 * v + k] + s * normals[3 * v + k]);
        }
    });
}

}  // namespace

UnsmoothedSurface record_unsmoothed_surface(const TriMesh& mesh, int threads) {
    UnsmoothedSurface surface;
    surface.labels = component_labels(mesh, &surface.components, threads);
    surface.volumes = component_volumes(mesh, surface.labels, surface.components, threads);
    surface.positions = mesh.vertices;
    return surface;
}

SmoothedNormals restore_component_volumes(TriMesh& mesh, const MeshAdjacency& adjacency, const UnsmoothedSurface& unsmoothed,
                                          const std::vector<float>& amount, double max_offset, int normal_iterations, int threads,
                                          const WallConstraints* walls, int newton_steps) {
    // Smoothed normals: offsets along raw vertex normals would print the triangulation's noise back in. The offsets
    // are small against the features, so the directions computed once serve every Newton step. Computed before
    // anything else, since the normals stage takes them even when there is nothing to restore.
    SmoothedNormals normals{area_weighted_normals(mesh, adjacency.vertex_triangles, threads), normal_iterations};
    smooth_normals(normals.values, adjacency.vertex_neighbours, normal_iterations, threads);
    const std::vector<double>& target = unsmoothed.volumes;
    const int32_t count = unsmoothed.components;
    if (count == 0 || mesh.num_triangles() == 0) return normals;
    std::vector<double> applied(static_cast<std::size_t>(count), 0.0);
    const std::vector<int32_t> origin = component_smallest_vertices(unsmoothed.labels, count, threads);
    for (int step = 0; step < newton_steps; ++step) {
        // One pass over the triangles per step: the rates come with the volumes (unused after the last step).
        const std::vector<double> sums = volumes_and_rates(mesh, unsmoothed.labels, count, origin, amount, threads);
        auto volume = [&](int32_t c) { return sums[2 * static_cast<std::size_t>(c)]; };
        auto rate = [&](int32_t c) { return sums[2 * static_cast<std::size_t>(c) + 1]; };
        // Within a few millionths (usually after the first step): a further step changes nothing worth its passes.
        bool converged = true;
        for (int32_t c = 0; c < count && converged; ++c)
            converged = std::fabs(target[c] - volume(c)) <= 1e-5 * std::fabs(target[c]);
        if (converged) break;
        std::vector<double> offset(static_cast<std::size_t>(count), 0.0);
        bool any = false;
        for (int32_t c = 0; c < count; ++c) {
            if (!(rate(c) > 0.0)) continue;
            double s = (target[c] - volume(c)) / rate(c);
            // Cap the accumulated offset: a component that smoothing collapsed is not blown back up from nothing.
            s = std::min(std::max(applied[c] + s, -max_offset), max_offset) - applied[c];
            if (!std::isfinite(s)) continue;
            applied[c] += s;
            offset[c] = s;
            any = any || s != 0.0;
        }
        if (!any) break;
        move_along_normals(mesh, unsmoothed.labels, offset, amount, normals.values, threads);
        if (walls) walls->apply(mesh.vertices.data(), mesh.num_vertices());
    }
    return normals;
}

int restoration_normal_iterations(const PostprocessParams& post) {
    const bool output_takes_them = post.normals && !post.sph_normals && post.normal_smoothing_iterations > 0;
    return output_takes_them ? post.normal_smoothing_iterations : 10;
}

std::size_t revert_collapsed_components(TriMesh& mesh, const UnsmoothedSurface& unsmoothed, int threads) {
    const std::vector<int32_t>& labels = unsmoothed.labels;
    const int32_t count = unsmoothed.components;
    std::vector<uint8_t> collapsed(static_cast<std::size_t>(count), 0);
    const int64_t nt = static_cast<int64_t>(mesh.num_triangles());
    std::vector<uint8_t> zero_area(static_cast<std::size_t>(nt), 0);
    parallel_blocks(nt, threads, kVertexBlock, [&](int64_t begin, int64_t end) {
        for (int64_t t = begin; t < end; ++t) zero_area[t] = triangle_has_zero_area(mesh.vertices.data(), &mesh.triangles[3 * t]);
    });
    if (parallel_count(nt, threads, [&](int64_t t) { return zero_area[t] != 0; }) > 0)  // almost never: no serial sweep
        for (int64_t t = 0; t < nt; ++t)
            if (zero_area[t]) collapsed[labels[mesh.triangles[3 * t]]] = 1;
    const std::vector<double> volumes = component_volumes(mesh, labels, count, threads);
    for (int32_t c = 0; c < count; ++c)  // turned inside out
        if (unsmoothed.volumes[c] != 0.0 && volumes[c] * unsmoothed.volumes[c] <= 0.0) collapsed[c] = 1;
    std::size_t reverted = 0;
    for (int32_t c = 0; c < count; ++c) reverted += collapsed[c];
    if (reverted == 0) return 0;
    for (std::size_t v = 0; v < mesh.num_vertices(); ++v)
        if (collapsed[labels[v]])
            for (int k = 0; k < 3; ++k) mesh.vertices[3 * v + k] = unsmoothed.positions[3 * v + k];
    return reverted;
}

}  // namespace meniscus
