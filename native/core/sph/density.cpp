#include "sph/density.h"

#include <array>
#include <cmath>
#include <utility>

#include "base/parallel.h"
#include "sph/lanes.h"

namespace meniscus {

ParticleDensities compute_densities(const ParticleGrid& grid, const CubicSplineKernel& kernel, int threads) {
    const std::size_t n = grid.size();
    ParticleDensities out;
    out.volumes.assign(n, 0.0f);
    out.neighbor_counts.assign(n, 0.0f);
    const float support_squared = kernel.support_squared();
    const float inverse_support = 1.0f / kernel.support();
    const float normalisation = kernel.value(0.0f);  // W(0) = 8 / (pi H^3): shapes are summed, scaled once
    const LanePositions lanes(grid, threads);
    const float *xs = lanes.x.data(), *ys = lanes.y.data(), *zs = lanes.z.data();
    parallel_for(static_cast<int64_t>(grid.num_cells()), threads, [&](int64_t cell) {
        const auto c = grid.cell_coords(static_cast<std::size_t>(cell));
        std::array<std::pair<std::size_t, std::size_t>, 27> ranges;
        int range_count = 0;
        grid.for_each_cell_in_box({c[0] - 1, c[1] - 1, c[2] - 1}, {c[0] + 1, c[1] + 1, c[2] + 1}, [&](std::size_t other) {
            ranges[range_count++] = {grid.cell_begin(other), grid.cell_end(other)};
        });
        for (std::size_t i = grid.cell_begin(cell); i < grid.cell_end(cell); ++i) {
            const float xi = xs[i], yi = ys[i], zi = zs[i];
            float shape_sum[kLanes] = {}, hat_sum[kLanes] = {};
            for (int k = 0; k < range_count; ++k) {
                const std::size_t end = ranges[k].second;
                for (std::size_t block = ranges[k].first; block < end; block += kLanes) {
                    const int valid_lanes = static_cast<int>(std::min<std::size_t>(kLanes, end - block));
                    const int self_lane = i >= block && i < block + kLanes ? static_cast<int>(i - block) : -1;
                    const float *bx = xs + block, *by = ys + block, *bz = zs + block;
                    for (int l = 0; l < kLanes; ++l) {
                        const float dx = xi - bx[l], dy = yi - by[l], dz = zi - bz[l];
                        const float d2 = dx * dx + dy * dy + dz * dz;
                        // 1 or 0 as a factor rather than a branch (positions are finite, so 0 * value is 0).
                        const float counts = static_cast<float>((l < valid_lanes) & (l != self_lane) & (d2 < support_squared));
                        const float q = std::sqrt(d2) * inverse_support;
                        shape_sum[l] += counts * CubicSplineKernel::shape_branch_free(q);
                        hat_sum[l] += counts * (1.0f - q);  // Eq. 10-11: linear hat with h = H
                    }
                }
            }
            float shape = 0.0f, count = 0.0f;
            for (int l = 0; l < kLanes; ++l) shape += shape_sum[l], count += hat_sum[l];
            out.volumes[i] = 1.0f / (normalisation * (1.0f + shape));  // rho_i / m_i = W(0) + sum_j W_ij
            out.neighbor_counts[i] = count;
        }
    }, 16);
    return out;
}

}  // namespace meniscus
