// Particle data laid out for neighbour loops that visit candidates kLanes at a time without a branch: only about
// 15 % of the particles in the 27 cells around a point lie within the support, and a branch per candidate
// mispredicts too often. Lane l sums the candidates j = l (mod kLanes) of each range and the lanes are added in
// order at the end: the same sum for any thread count.
#pragma once
#include <algorithm>
#include <vector>

#include "sph/neighborhood.h"

namespace meniscus {

constexpr int kLanes = 8;

// Sorted particle coordinates as separate x, y, z arrays, padded by one block of lanes.
struct LanePositions {
    std::vector<float> x, y, z;
    explicit LanePositions(const ParticleGrid& grid) : x(grid.size() + kLanes), y(grid.size() + kLanes), z(grid.size() + kLanes) {
        for (std::size_t j = 0; j < grid.size(); ++j) x[j] = grid.position(j)[0], y[j] = grid.position(j)[1], z[j] = grid.position(j)[2];
    }
};

// A per-particle array padded by one block of zeros, so that lane loops may read past the last particle.
inline std::vector<float> padded(const float* values, std::size_t count) {
    std::vector<float> out(count + kLanes, 0.0f);
    std::copy(values, values + count, out.begin());
    return out;
}

}  // namespace meniscus
