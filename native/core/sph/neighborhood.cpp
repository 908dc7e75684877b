#include "sph/neighborhood.h"

#include <array>
#include <cmath>
#include <limits>
#include <numeric>
#include <string>

#include "base/errors.h"
#include "base/parallel.h"

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

// Stable LSD radix sort of (dense cell index, input index) pairs by the cell index, 8 bits per pass over the bits
// in use. The pairs arrive in input order, so the result is ordered by (cell, input index): a total order, the
// same for any thread count. Several times faster than a comparison sort for a million particles.
void radix_sort_by_cell(std::vector<std::pair<uint64_t, uint32_t>>& items, uint64_t largest_key) {
    std::vector<std::pair<uint64_t, uint32_t>> buffer(items.size());
    for (int shift = 0; shift < 64 && (largest_key >> shift) != 0; shift += 8) {
        std::array<std::size_t, 257> start{};
        for (const auto& item : items) ++start[((item.first >> shift) & 0xff) + 1];
        for (int digit = 0; digit < 256; ++digit) start[digit + 1] += start[digit];
        for (const auto& item : items) buffer[start[(item.first >> shift) & 0xff]++] = item;
        items.swap(buffer);
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

    // Sorted by (cell, input index): a total order, so the result does not depend on the thread count. The radix
    // sort runs on a dense index of the cell in the bounding box of cells (z, then y, then x: the order of the packed
    // keys), which needs only as many passes as its bits.
    std::vector<std::pair<uint64_t, uint32_t>> order(m);
    const uint64_t ex = static_cast<uint64_t>(extent_[0]), ey = static_cast<uint64_t>(extent_[1]);
    parallel_for(static_cast<int64_t>(m), threads, [&](int64_t s) {
        const uint64_t x = static_cast<uint64_t>(cells[3 * s] - lo[0]), y = static_cast<uint64_t>(cells[3 * s + 1] - lo[1]),
                       z = static_cast<uint64_t>(cells[3 * s + 2] - lo[2]);
        order[s] = {(z * ey + y) * ex + x, selected[s]};
    }, 4096);
    radix_sort_by_cell(order, ex * ey * static_cast<uint64_t>(extent_[2]) - 1);
    for (auto& item : order) {  // back to packed keys, which the cell lookups use
        const uint64_t x = item.first % ex, y = item.first / ex % ey, z = item.first / ex / ey;
        item.first = pack(static_cast<int64_t>(x) + lo[0], static_cast<int64_t>(y) + lo[1], static_cast<int64_t>(z) + lo[2]);
    }

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
