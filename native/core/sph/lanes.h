// Particle data laid out for neighbour loops that visit candidates kLanes at a time without a branch: only about
// 15 % of the particles in the 27 cells around a point lie within the support, and a branch per candidate
// mispredicts too often. Lane l sums the candidates j = l (mod kLanes) of each range and the lanes are added in
// order at the end: the same sum for any thread count.
#pragma once
#include <algorithm>
#include <vector>

#include "base/parallel.h"
#include "base/uninitialized_vector.h"
#include "sph/neighborhood.h"

namespace meniscus {

constexpr int kLanes = 8;

// Sorted particle coordinates as separate x, y, z arrays, padded by one block of lanes (zeros), filled in parallel.
struct LanePositions {
    UninitializedVector<float> x, y, z;
    LanePositions(const ParticleGrid& grid, int threads) : x(grid.size() + kLanes), y(grid.size() + kLanes), z(grid.size() + kLanes) {
        const int64_t n = static_cast<int64_t>(grid.size());
        parallel_blocks(n, threads, kFirstTouchBlock, [&](int64_t begin, int64_t end) {
            for (int64_t j = begin; j < end; ++j) x[j] = grid.position(j)[0], y[j] = grid.position(j)[1], z[j] = grid.position(j)[2];
        });
        std::fill(x.begin() + n, x.end(), 0.0f), std::fill(y.begin() + n, y.end(), 0.0f), std::fill(z.begin() + n, z.end(), 0.0f);
    }
};

// A per-particle array padded by one block of zeros, so that lane loops may read past the last particle.
inline UninitializedVector<float> padded(const float* values, std::size_t count, int threads) {
    UninitializedVector<float> out(count + kLanes);
    parallel_blocks(static_cast<int64_t>(count), threads, kFirstTouchBlock,
                    [&](int64_t begin, int64_t end) { std::copy(values + begin, values + end, out.data() + begin); });
    std::fill(out.begin() + static_cast<std::ptrdiff_t>(count), out.end(), 0.0f);
    return out;
}

}  // namespace meniscus
