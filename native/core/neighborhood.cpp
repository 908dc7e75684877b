#include "neighborhood.h"

#include <cmath>
#include <limits>
#include <numeric>
#include <string>

#include "errors.h"
#include "parallel.h"

namespace meniscus {

namespace {
int64_t floor_cell(double x, double cell_size) { return static_cast<int64_t>(std::floor(x / cell_size)); }
}  // namespace

std::array<int64_t, 3> ParticleGrid::cell_of(const float* x) const {
    return {floor_cell(x[0], cell_size_), floor_cell(x[1], cell_size_), floor_cell(x[2], cell_size_)};
}

std::array<int64_t, 3> ParticleGrid::cell_coords(std::size_t cell) const {
    const uint64_t key = cell_keys_[cell];
    const uint64_t mask = (uint64_t(1) << kAxisBits) - 1;
    return {origin_[0] + int64_t(key & mask), origin_[1] + int64_t((key >> kAxisBits) & mask),
            origin_[2] + int64_t(key >> (2 * kAxisBits))};
}

namespace {

// Sorts pieces in parallel, then merges neighbouring pieces pairwise. The keys are unique (cell key, input index),
// so there is one sorted order and the result does not depend on how many pieces there were.
void sort_in_parallel(std::vector<std::pair<uint64_t, uint32_t>>& items, int threads) {
    const int64_t n = static_cast<int64_t>(items.size());
    const int64_t pieces = std::max<int64_t>(1, std::min<int64_t>(resolve_threads(threads), n / 65536));
    if (pieces <= 1) {
        std::sort(items.begin(), items.end());
        return;
    }
    auto bound = [&](int64_t p) { return items.begin() + std::min(n, n * p / pieces); };
    parallel_for(pieces, threads, [&](int64_t p) { std::sort(bound(p), bound(p + 1)); });
    for (int64_t width = 1; width < pieces; width *= 2) {
        const int64_t groups = (pieces + 2 * width - 1) / (2 * width);
        parallel_for(groups, threads, [&](int64_t g) {
            const int64_t first = 2 * width * g, middle = std::min(pieces, first + width), last = std::min(pieces, first + 2 * width);
            if (middle < last) std::inplace_merge(bound(first), bound(middle), bound(last));
        });
    }
}

}  // namespace

ParticleGrid::ParticleGrid(const PositionsView& input, double cell_size, int threads, const std::vector<uint8_t>* keep)
    : cell_size_(cell_size) {
    if (!(cell_size > 0.0) || !std::isfinite(cell_size)) throw InputError("cell size must be positive and finite, got " + std::to_string(cell_size));
    const std::size_t n = input.count;
    if (n >= std::numeric_limits<uint32_t>::max()) throw InputError("too many particles: " + std::to_string(n) + " (at most 4294967294)");

    // Selected particles, in input order.
    std::vector<uint32_t> selected;
    selected.reserve(n);
    for (std::size_t i = 0; i < n; ++i)
        if (!keep || (*keep)[i]) selected.push_back(static_cast<uint32_t>(i));
    const std::size_t m = selected.size();

    std::array<int64_t, 3> lo{std::numeric_limits<int64_t>::max(), std::numeric_limits<int64_t>::max(), std::numeric_limits<int64_t>::max()};
    std::array<int64_t, 3> hi{std::numeric_limits<int64_t>::min(), std::numeric_limits<int64_t>::min(), std::numeric_limits<int64_t>::min()};
    std::vector<int64_t> cells(3 * m);
    for (std::size_t s = 0; s < m; ++s) {
        for (int k = 0; k < 3; ++k) {
            // Positions are stored as float; the cell is computed from the stored value so that queries agree.
            const double x = static_cast<float>(input.coord(selected[s], k));
            const double c = std::floor(x / cell_size);
            if (!(std::fabs(c) < 4.0e15)) throw InputError("particle " + std::to_string(selected[s]) + " has a coordinate too large for the grid: " + std::to_string(x));
            cells[3 * s + k] = static_cast<int64_t>(c);
            lo[k] = std::min(lo[k], cells[3 * s + k]);
            hi[k] = std::max(hi[k], cells[3 * s + k]);
        }
    }
    if (m == 0) {
        cell_start_.push_back(0);
        return;
    }
    for (int k = 0; k < 3; ++k) {
        origin_[k] = lo[k];
        extent_[k] = hi[k] - lo[k] + 1;
        if (extent_[k] > (int64_t(1) << kAxisBits))
            throw InputError("the particles span " + std::to_string(extent_[k]) + " kernel supports along axis " + std::string(1, "xyz"[k]) +
                             " (at most " + std::to_string(int64_t(1) << kAxisBits) +
                             "): is the particle radius in the units of the positions, or are there stray particles far away?");
    }

    // Sort by (cell key, input index): a total order, so the result does not depend on the thread count.
    std::vector<std::pair<uint64_t, uint32_t>> order(m);
    parallel_for(static_cast<int64_t>(m), threads, [&](int64_t s) {
        order[s] = {pack(cells[3 * s], cells[3 * s + 1], cells[3 * s + 2]), selected[s]};
    }, 4096);
    sort_in_parallel(order, threads);

    positions_.resize(3 * m);
    original_index_.resize(m);
    parallel_for(static_cast<int64_t>(m), threads, [&](int64_t s) {
        const uint32_t i = order[s].second;
        original_index_[s] = i;
        for (int k = 0; k < 3; ++k) positions_[3 * s + k] = static_cast<float>(input.coord(i, k));
    }, 4096);
    for (std::size_t s = 0; s < m; ++s) {
        if (s == 0 || order[s].first != order[s - 1].first) {
            cell_keys_.push_back(order[s].first);
            cell_start_.push_back(static_cast<uint32_t>(s));
        }
    }
    cell_start_.push_back(static_cast<uint32_t>(m));
}

}  // namespace meniscus
