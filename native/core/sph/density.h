// The density pass (paper Sec. 3.1, and Eq. 10-11 of Sec. 3.2 on the way): one loop over every particle's
// neighbours gives its SPH density, as the volume V_j = m_j / rho_j the colour field and the interpolation weigh
// it with, and its hat-weighted neighbour count, from which the feature weights are made.
#pragma once
#include <vector>

#include "sph/kernel.h"
#include "sph/neighborhood.h"

namespace meniscus {

// Per particle, in the grid's sorted order.
struct ParticleDensities {
    std::vector<float> volumes;          // m_j / rho_j, with rho_j / m_j = W(0) + sum_k W_jk (no rest density needed)
    std::vector<float> neighbor_counts;  // sum_k (1 - |x_j - x_k| / H) over the neighbours k within H (Eq. 10-11, h = H)
};

ParticleDensities compute_densities(const ParticleGrid& grid, const CubicSplineKernel& kernel, int threads);

}  // namespace meniscus
