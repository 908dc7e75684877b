#include "sph/interpolation.h"

#include <algorithm>
#include <cmath>
#include <string>

#include "base/errors.h"
#include "base/parallel.h"
#include "sph/lanes.h"

namespace meniscus {

namespace {

// Calls at_point(p, cache) for every point p in blocks of consecutive points, each block with its own cache of
// neighbour cells (see ParticleGrid::neighbor_cells).
template <class AtPoint>
void for_each_point(const std::vector<float>& points, int threads, AtPoint&& at_point) {
    constexpr int64_t kBlock = 256;
    const int64_t n = static_cast<int64_t>(points.size() / 3);
    parallel_for((n + kBlock - 1) / kBlock, threads, [&](int64_t block) {
        ParticleGrid::NeighborCells cache;
        const int64_t end = std::min<int64_t>(n, (block + 1) * kBlock);
        for (int64_t p = block * kBlock; p < end; ++p) at_point(p, cache);
    });
}

void require_components(int components, const char* what) {
    if (components < 1 || components > 16) throw InputError(std::string(what) + " takes 1 to 16 components, got " + std::to_string(components));
}

// Eq. 7 for any layout of the values: value_at(j) gives sorted particle j's `components` floats.
template <class ValueAt>
void interpolate(const SphField& field, ValueAt&& value_at, int components, const std::vector<float>& points, std::vector<float>& out,
                 int threads) {
    require_components(components, "interpolation");
    out.assign(points.size() / 3 * static_cast<std::size_t>(components), 0.0f);
    const CubicSplineKernel& kernel = field.kernel;
    for_each_point(points, threads, [&](int64_t p, ParticleGrid::NeighborCells& cache) {
        double weight_sum = 0.0, sum[16];
        std::fill(sum, sum + components, 0.0);
        field.grid.for_each_neighbor(&points[3 * p], kernel.support(), cache, [&](std::size_t j, float d2) {
            const double w = double(field.volumes[j]) * kernel.value(std::sqrt(d2));
            weight_sum += w;
            const float* v = value_at(j);
            for (int k = 0; k < components; ++k) sum[k] += w * v[k];
        });
        if (weight_sum > 0.0)
            for (int k = 0; k < components; ++k) out[static_cast<std::size_t>(p) * components + k] = static_cast<float>(sum[k] / weight_sum);
    });
}

// Eq. 7 for one value per sorted particle (the feature weights' counts, at every vertex): the branch-free lane loop
// of the density pass.
void interpolate_scalar_sorted(const SphField& field, const float* values, const std::vector<float>& points, std::vector<float>& out,
                               int threads) {
    out.assign(points.size() / 3, 0.0f);
    const float support_squared = field.kernel.support_squared(), inverse_support = 1.0f / field.kernel.support();
    const LanePositions lanes(field.grid, threads);
    const UninitializedVector<float> volumes = padded(field.volumes.data(), field.grid.size(), threads);
    const UninitializedVector<float> sorted_values = padded(values, field.grid.size(), threads);
    for_each_point(points, threads, [&](int64_t p, ParticleGrid::NeighborCells& cache) {
        const float px = points[3 * p], py = points[3 * p + 1], pz = points[3 * p + 2];
        const ParticleGrid::NeighborCells& cells = field.grid.neighbor_cells(&points[3 * p], cache);
        float weight_sum[kLanes] = {}, value_sum[kLanes] = {};
        for (int k = 0; k < cells.count; ++k) {
            const std::size_t range_end = cells.ranges[k].second;
            for (std::size_t first = cells.ranges[k].first; first < range_end; first += kLanes) {
                const int valid_lanes = static_cast<int>(std::min<std::size_t>(kLanes, range_end - first));
                const float *bx = lanes.x.data() + first, *by = lanes.y.data() + first, *bz = lanes.z.data() + first;
                const float *bv = volumes.data() + first, *bw = sorted_values.data() + first;
                for (int l = 0; l < kLanes; ++l) {
                    const float dx = px - bx[l], dy = py - by[l], dz = pz - bz[l];
                    const float d2 = dx * dx + dy * dy + dz * dz;
                    const float counts = static_cast<float>((l < valid_lanes) & (d2 < support_squared));
                    const float w = counts * bv[l] * CubicSplineKernel::shape_branch_free(std::sqrt(d2) * inverse_support);  // V_j W_ij / W(0)
                    weight_sum[l] += w;
                    value_sum[l] += w * bw[l];
                }
            }
        }
        float weight = 0.0f, value = 0.0f;
        for (int l = 0; l < kLanes; ++l) weight += weight_sum[l], value += value_sum[l];
        if (weight > 0.0f) out[static_cast<std::size_t>(p)] = value / weight;  // Eq. 7: 0th-order (Shepard) correction
    });
}

}  // namespace

void interpolate_at_points(const SphField& field, const float* values, int components, const std::vector<float>& points,
                           std::vector<float>& out, int threads) {
    interpolate(field, [&](std::size_t j) { return values + static_cast<std::size_t>(field.grid.original_index(j)) * components; },
                components, points, out, threads);
}

void interpolate_sorted_at_points(const SphField& field, const float* values, int components, const std::vector<float>& points,
                                  std::vector<float>& out, int threads) {
    if (components == 1) interpolate_scalar_sorted(field, values, points, out, threads);
    else interpolate(field, [&](std::size_t j) { return values + j * components; }, components, points, out, threads);
}

void nearest_particle_at_points(const SphField& field, const float* values, int components, const std::vector<float>& points,
                                std::vector<float>& out, int threads) {
    require_components(components, "attribute transfer");
    out.assign(points.size() / 3 * static_cast<std::size_t>(components), 0.0f);
    for_each_point(points, threads, [&](int64_t p, ParticleGrid::NeighborCells& cache) {
        float nearest_d2 = INFINITY;
        std::size_t nearest = 0;
        // Neighbours come in sorted order: the strict < keeps the first of equally near particles.
        field.grid.for_each_neighbor(&points[3 * p], field.kernel.support(), cache, [&](std::size_t j, float d2) {
            if (d2 < nearest_d2) {
                nearest_d2 = d2;
                nearest = j;
            }
        });
        if (nearest_d2 == INFINITY) return;
        const float* v = values + static_cast<std::size_t>(field.grid.original_index(nearest)) * components;
        std::copy(v, v + components, out.begin() + static_cast<std::ptrdiff_t>(p) * components);
    });
}

void validate_attribute_inputs(const std::vector<AttributeInput>& attributes, std::size_t particle_count) {
    for (const AttributeInput& a : attributes) {
        if (a.components < 1 || a.components > 16)
            throw InputError("attribute '" + a.name + "' must have 1 to 16 components, got " + std::to_string(a.components));
        if (!a.values && particle_count > 0) throw InputError("attribute '" + a.name + "' has no data");
    }
}

std::vector<Attribute> transfer_attributes(const SphField& field, const std::vector<AttributeInput>& attributes,
                                           const std::vector<float>& points, int threads) {
    std::vector<Attribute> out;
    for (const AttributeInput& a : attributes) {
        Attribute transferred{a.name, a.components, {}, a.integral};
        if (a.integral) nearest_particle_at_points(field, a.values, a.components, points, transferred.values, threads);
        else interpolate_at_points(field, a.values, a.components, points, transferred.values, threads);
        out.push_back(std::move(transferred));
    }
    return out;
}

std::vector<float> colour_field_normals(const SphField& field, const std::vector<float>& points, int threads) {
    std::vector<float> normals(3 * (points.size() / 3), 0.0f);
    const CubicSplineKernel& kernel = field.kernel;
    for_each_point(points, threads, [&](int64_t p, ParticleGrid::NeighborCells& cache) {
        const float* x = &points[3 * p];
        double g[3] = {0, 0, 0};
        field.grid.for_each_neighbor(x, kernel.support(), cache, [&](std::size_t j, float d2) {
            const float d = std::sqrt(d2);
            if (d <= 0.0f) return;
            const double s = double(field.volumes[j]) * kernel.derivative(d) / d;
            const float* xj = field.grid.position(j);
            for (int k = 0; k < 3; ++k) g[k] += s * (double(x[k]) - double(xj[k]));
        });
        // The colour field decreases outwards: the outward normal is minus its gradient.
        const double length = std::sqrt(g[0] * g[0] + g[1] * g[1] + g[2] * g[2]);
        if (length > 0.0)
            for (int k = 0; k < 3; ++k) normals[3 * p + k] = static_cast<float>(-g[k] / length);
    });
    return normals;
}

}  // namespace meniscus
