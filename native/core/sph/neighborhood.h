// Particle grid: particles sorted into cubic cells of edge H (the kernel support), stored sparsely (only occupied
// cells), so memory follows the particle count, never the bounding box. It is built once per frame and reused by
// every stage that needs particles near a point: densities, the level set, the feature weights, and the
// interpolation of attributes to mesh vertices (paper Sec. 4).
#pragma once
#include <algorithm>
#include <array>
#include <cstddef>
#include <climits>
#include <cstdint>
#include <vector>

#include "base/uninitialized_vector.h"
#include "sph/particles.h"

namespace meniscus {

class ParticleGrid {
public:
    // Sorts the finite particles of `positions` into cells. `keep` (optional, size count) selects particles.
    ParticleGrid(const PositionsView& positions, double cell_size, int threads, const std::vector<uint8_t>* keep = nullptr);

    std::size_t size() const { return original_index_.size(); }
    double cell_size() const { return cell_size_; }
    std::size_t num_cells() const { return cell_keys_.size(); }
    // The box of occupied cells: smallest cell coordinates and the number of cells per axis (zero without particles).
    const std::array<int64_t, 3>& cell_origin() const { return origin_; }
    const std::array<int64_t, 3>& cell_extent() const { return extent_; }

    // Sorted particle j: position and index in the caller's array.
    const float* position(std::size_t j) const { return &positions_[3 * j]; }
    const UninitializedVector<float>& positions() const { return positions_; }
    uint32_t original_index(std::size_t j) const { return original_index_[j]; }
    const UninitializedVector<uint32_t>& original_indices() const { return original_index_; }

    // Cell coordinates (absolute integer lattice coordinates of edge cell_size).
    std::array<int64_t, 3> cell_of(const float* x) const;
    std::array<int64_t, 3> cell_coords(std::size_t cell) const;
    // Particle range [begin, end) of an occupied cell index.
    std::size_t cell_begin(std::size_t cell) const { return cell_start_[cell]; }
    std::size_t cell_end(std::size_t cell) const { return cell_start_[cell + 1]; }

    // Calls visit(cell_index) for every occupied cell in the box of cell coordinates [lo, hi] (inclusive), in
    // ascending key order, which is the order of the sorted particles: sums over them are reproducible.
    template <class Visit>
    void for_each_cell_in_box(const std::array<int64_t, 3>& lo, const std::array<int64_t, 3>& hi, Visit&& visit) const {
        const int64_t x0 = std::max<int64_t>(lo[0], origin_[0]), x1 = std::min<int64_t>(hi[0], origin_[0] + extent_[0] - 1);
        const int64_t y0 = std::max<int64_t>(lo[1], origin_[1]), y1 = std::min<int64_t>(hi[1], origin_[1] + extent_[1] - 1);
        const int64_t z0 = std::max<int64_t>(lo[2], origin_[2]), z1 = std::min<int64_t>(hi[2], origin_[2] + extent_[2] - 1);
        if (x0 > x1 || y0 > y1 || z0 > z1) return;
        for (int64_t z = z0; z <= z1; ++z)
            for (int64_t y = y0; y <= y1; ++y) {
                const uint64_t first = pack(x0, y, z), last = pack(x1, y, z);
                auto it = std::lower_bound(cell_keys_.begin(), cell_keys_.end(), first);
                for (; it != cell_keys_.end() && *it <= last; ++it) visit(static_cast<std::size_t>(it - cell_keys_.begin()));
            }
    }

    // The particle ranges of the 27 cells around one cell. Queries from nearby points (mesh vertices come in
    // spatially coherent order) reuse them instead of searching the cell keys again.
    struct NeighborCells {
        std::array<int64_t, 3> cell{INT64_MIN, INT64_MIN, INT64_MIN};
        int count = 0;
        std::array<std::pair<uint32_t, uint32_t>, 27> ranges{};
    };

    // The ranges of sorted particles in the 27 cells around x's cell, kept in `cache` while x stays in that cell.
    const NeighborCells& neighbor_cells(const float* x, NeighborCells& cache) const {
        const auto c = cell_of(x);
        if (c != cache.cell) {
            cache.cell = c;
            cache.count = 0;
            for_each_cell_in_box({c[0] - 1, c[1] - 1, c[2] - 1}, {c[0] + 1, c[1] + 1, c[2] + 1},
                                 [&](std::size_t cell) { cache.ranges[cache.count++] = {cell_start_[cell], cell_start_[cell + 1]}; });
        }
        return cache;
    }

    // Calls visit(j, squared_distance) for every sorted particle j within `radius` (< cell_size) of x, cell by cell
    // in the order of for_each_cell_in_box.
    template <class Visit>
    void for_each_neighbor(const float* x, float radius, NeighborCells& cache, Visit&& visit) const {
        neighbor_cells(x, cache);
        const float r2 = radius * radius;
        for (int k = 0; k < cache.count; ++k)
            for (std::size_t j = cache.ranges[k].first; j < cache.ranges[k].second; ++j) {
                const float* p = &positions_[3 * j];
                const float dx = x[0] - p[0], dy = x[1] - p[1], dz = x[2] - p[2];
                const float d2 = dx * dx + dy * dy + dz * dz;
                if (d2 < r2) visit(j, d2);
            }
    }

    // Calls visit(j, squared_distance) for every sorted particle j within `radius` (< cell_size) of x.
    template <class Visit>
    void for_each_neighbor(const float* x, float radius, Visit&& visit) const {
        NeighborCells cache;
        for_each_neighbor(x, radius, cache, visit);
    }

    // Lattice coordinate bits per axis: the particles may span up to 2^21 cells per axis.
    static constexpr int kAxisBits = 21;

private:
    uint64_t pack(int64_t x, int64_t y, int64_t z) const {
        return (static_cast<uint64_t>(z - origin_[2]) << (2 * kAxisBits)) | (static_cast<uint64_t>(y - origin_[1]) << kAxisBits) |
               static_cast<uint64_t>(x - origin_[0]);
    }

    double cell_size_;
    std::array<int64_t, 3> origin_{};   // smallest occupied cell coordinates
    std::array<int64_t, 3> extent_{};   // occupied cell range per axis
    UninitializedVector<float> positions_;  // sorted by cell key, then by original index (filled in parallel)
    UninitializedVector<uint32_t> original_index_;
    std::vector<uint64_t> cell_keys_;   // ascending, occupied cells only
    std::vector<uint32_t> cell_start_;  // num_cells + 1
};

}  // namespace meniscus
