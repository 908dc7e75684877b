#include "sph/neighborhood.h"

#include <array>
#include <cmath>
#include <limits>
#include <numeric>
#include <string>

#include "base/compaction.h"
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

constexpr int64_t kGridBlock = int64_t{1} << 16;

// A particle's cell key and input index (a plain struct rather than a std::pair, whose default constructor writes
// zeros: the sort's arrays are filled by parallel loops, which should be the first to touch their pages).
struct KeyedParticle {
    uint64_t key;
    uint32_t index;
};

// Stable LSD radix sort of (dense cell index, input index) pairs by the cell index, 8 bits per pass over the bits
// in use. The pairs arrive in input order, so the result is ordered by (cell, input index): a total order, the
// same for any thread count. Several times faster than a comparison sort for a million particles. Each pass counts
// digits per fixed block in parallel; a block's items of one digit go after those of the same digit in earlier
// blocks, which is where a serial stable pass puts them.
void radix_sort_by_cell(UninitializedVector<KeyedParticle>& items, uint64_t largest_key, int threads) {
    const int64_t n = static_cast<int64_t>(items.size());
    const int64_t blocks = (n + kGridBlock - 1) / kGridBlock;
    UninitializedVector<KeyedParticle> buffer(items.size());  // every item written by the first pass
    std::vector<std::array<std::size_t, 256>> next(static_cast<std::size_t>(blocks));
    for (int shift = 0; shift < 64 && (largest_key >> shift) != 0; shift += 8) {
        parallel_for(blocks, threads, [&](int64_t b) {
            std::array<std::size_t, 256>& count = next[static_cast<std::size_t>(b)];
            count.fill(0);
            for (int64_t i = b * kGridBlock, end = std::min(n, i + kGridBlock); i < end; ++i) ++count[(items[i].key >> shift) & 0xff];
        });
        std::size_t start = 0;  // digit-major: all blocks' 0s, then all blocks' 1s, ...
        for (int digit = 0; digit < 256; ++digit)
            for (auto& count : next) {
                const std::size_t c = count[digit];
                count[digit] = start;
                start += c;
            }
        parallel_for(blocks, threads, [&](int64_t b) {
            std::array<std::size_t, 256>& at = next[static_cast<std::size_t>(b)];
            for (int64_t i = b * kGridBlock, end = std::min(n, i + kGridBlock); i < end; ++i) buffer[at[(items[i].key >> shift) & 0xff]++] = items[i];
        });
        items.swap(buffer);
    }
}

// Cell coordinate bounds of a block of particles, and its first particle whose coordinate is too large for the grid.
struct CellBounds {
    std::array<int64_t, 3> lo{std::numeric_limits<int64_t>::max(), std::numeric_limits<int64_t>::max(), std::numeric_limits<int64_t>::max()};
    std::array<int64_t, 3> hi{std::numeric_limits<int64_t>::min(), std::numeric_limits<int64_t>::min(), std::numeric_limits<int64_t>::min()};
    std::size_t first_too_large = std::numeric_limits<std::size_t>::max();  // a selected index
};

}  // namespace

ParticleGrid::ParticleGrid(const PositionsView& input, double cell_size, int threads, const std::vector<uint8_t>* keep)
    : cell_size_(cell_size) {
    if (!(cell_size > 0.0) || !std::isfinite(cell_size)) throw InputError("cell size must be positive and finite, got " + std::to_string(cell_size));
    const std::size_t n = input.count;
    if (n >= std::numeric_limits<uint32_t>::max()) throw InputError("too many particles: " + std::to_string(n) + " (at most 4294967294)");

    // Selected particles, in input order.
    const std::vector<uint32_t> selected = kept_indices<uint32_t>(static_cast<int64_t>(n), threads, [&](int64_t i) { return !keep || (*keep)[i]; });
    const std::size_t m = selected.size();

    // Cells, and their bounds folded over fixed blocks (minima and maxima: any order gives the same). A coordinate too
    // large is reported for the first such particle, as a serial loop would.
    UninitializedVector<int64_t> cells(3 * m);  // written below, or a particle is refused
    const CellBounds bounds = ordered_block_reduce(
        static_cast<int64_t>(m), threads, kGridBlock, CellBounds{},
        [&](int64_t begin, int64_t end, CellBounds& block) {
            for (int64_t s = begin; s < end; ++s)
                for (int k = 0; k < 3; ++k) {
                    // Positions are stored as float; the cell is computed from the stored value so that queries agree.
                    const double x = static_cast<float>(input.coord(selected[s], k));
                    const double c = std::floor(x / cell_size);
                    if (!(std::fabs(c) < 4.0e15)) {
                        block.first_too_large = std::min(block.first_too_large, static_cast<std::size_t>(s));
                        continue;
                    }
                    cells[3 * s + k] = static_cast<int64_t>(c);
                    block.lo[k] = std::min(block.lo[k], cells[3 * s + k]);
                    block.hi[k] = std::max(block.hi[k], cells[3 * s + k]);
                }
        },
        [](CellBounds& total, const CellBounds& block) {
            for (int k = 0; k < 3; ++k) {
                total.lo[k] = std::min(total.lo[k], block.lo[k]);
                total.hi[k] = std::max(total.hi[k], block.hi[k]);
            }
            total.first_too_large = std::min(total.first_too_large, block.first_too_large);
        });
    if (bounds.first_too_large < m) {
        const std::size_t s = bounds.first_too_large;
        for (int k = 0; k < 3; ++k) {
            const double x = static_cast<float>(input.coord(selected[s], k));
            if (!(std::fabs(std::floor(x / cell_size)) < 4.0e15))
                throw InputError("particle " + std::to_string(selected[s]) + " has a coordinate too large for the grid: " + std::to_string(x));
        }
    }
    const std::array<int64_t, 3>& lo = bounds.lo;
    const std::array<int64_t, 3>& hi = bounds.hi;
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
    UninitializedVector<KeyedParticle> order(m);
    const uint64_t ex = static_cast<uint64_t>(extent_[0]), ey = static_cast<uint64_t>(extent_[1]);
    parallel_for(static_cast<int64_t>(m), threads, [&](int64_t s) {
        const uint64_t x = static_cast<uint64_t>(cells[3 * s] - lo[0]), y = static_cast<uint64_t>(cells[3 * s + 1] - lo[1]),
                       z = static_cast<uint64_t>(cells[3 * s + 2] - lo[2]);
        order[s] = KeyedParticle{(z * ey + y) * ex + x, selected[s]};
    }, 4096);
    radix_sort_by_cell(order, ex * ey * static_cast<uint64_t>(extent_[2]) - 1, threads);
    parallel_for(static_cast<int64_t>(m), threads, [&](int64_t s) {  // back to packed keys, which the cell lookups use
        auto& item = order[s];
        const uint64_t x = item.key % ex, y = item.key / ex % ey, z = item.key / ex / ey;
        item.key = pack(static_cast<int64_t>(x) + lo[0], static_cast<int64_t>(y) + lo[1], static_cast<int64_t>(z) + lo[2]);
    }, 4096);

    positions_.resize(3 * m);
    original_index_.resize(m);
    parallel_for(static_cast<int64_t>(m), threads, [&](int64_t s) {
        const uint32_t i = order[s].index;
        original_index_[s] = i;
        for (int k = 0; k < 3; ++k) positions_[3 * s + k] = static_cast<float>(input.coord(i, k));
    }, 4096);
    cell_start_ = kept_indices<uint32_t>(static_cast<int64_t>(m), threads, [&](int64_t s) { return s == 0 || order[s].key != order[s - 1].key; });
    cell_keys_.resize(cell_start_.size());
    parallel_for(static_cast<int64_t>(cell_start_.size()), threads, [&](int64_t c) { cell_keys_[c] = order[cell_start_[c]].key; }, 4096);
    cell_start_.push_back(static_cast<uint32_t>(m));
}

}  // namespace meniscus
