// Particles grouped into clusters: two particles closer than a distance are in the same cluster, and so are the
// particles chained by such pairs. With the kernel support as the distance, every connected piece of the surface
// lies within one cluster (a piece of surface needs overlapping kernels), so a cluster's particle count is a stable
// size for the stray-blob filter: a droplet keeps its count while it moves.
#pragma once
#include <cstdint>
#include <vector>

#include "sph/neighborhood.h"

namespace meniscus {

struct ParticleClusters {
    std::vector<int32_t> of_particle;  // cluster of each sorted particle (grid order), numbered 0.. in order of their
                                       // first particle, so the numbering is the same for any thread count
    std::vector<int32_t> sizes;        // particles per cluster
};

ParticleClusters cluster_particles(const ParticleGrid& grid, double distance);

}  // namespace meniscus
