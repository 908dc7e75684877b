#include "sph/clusters.h"

#include <algorithm>
#include <numeric>

namespace meniscus {

namespace {

// Union-find with the smaller index as the root, so the roots do not depend on the order of the unions.
int32_t find_root(std::vector<int32_t>& parent, int32_t i) {
    while (parent[i] != i) {
        parent[i] = parent[parent[i]];
        i = parent[i];
    }
    return i;
}

}  // namespace

ParticleClusters cluster_particles(const ParticleGrid& grid, double distance) {
    const int32_t n = static_cast<int32_t>(grid.size());
    std::vector<int32_t> parent(static_cast<std::size_t>(n));
    std::iota(parent.begin(), parent.end(), 0);
    // The grid's 27-cell neighbourhood covers distances up to its cell size (the kernel support).
    const float radius = static_cast<float>(std::min(distance, grid.cell_size()));
    ParticleGrid::NeighborCells cache;
    for (int32_t i = 0; i < n; ++i) {
        grid.for_each_neighbor(grid.position(static_cast<std::size_t>(i)), radius, cache, [&](std::size_t j, float) {
            if (static_cast<int32_t>(j) <= i) return;
            const int32_t a = find_root(parent, i), b = find_root(parent, static_cast<int32_t>(j));
            if (a != b) parent[std::max(a, b)] = std::min(a, b);
        });
    }
    ParticleClusters clusters;
    clusters.of_particle.assign(static_cast<std::size_t>(n), -1);
    std::vector<int32_t> number(static_cast<std::size_t>(n), -1);
    for (int32_t i = 0; i < n; ++i) {
        const int32_t root = find_root(parent, i);
        if (number[root] < 0) {
            number[root] = static_cast<int32_t>(clusters.sizes.size());
            clusters.sizes.push_back(0);
        }
        clusters.of_particle[i] = number[root];
        ++clusters.sizes[number[root]];
    }
    return clusters;
}

}  // namespace meniscus
