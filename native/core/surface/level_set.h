// The level set of the reconstruction (paper Sec. 3.1): the colour field of Eq. 1, phi(x) = sum_j V_j W(x - x_j),
// sampled at the lattice points of the bricks it can cross, for marching cubes (bricks.h).
#pragma once
#include <vector>

#include "sph/interpolation.h"
#include "sph/neighborhood.h"
#include "surface/bricks.h"

namespace meniscus {

// The bricks within the kernel support plus one cube of a particle's cell (sorted by coords_less, unique). The
// extra cube guarantees that every edge with a sign change starts in one of them, so each vertex has an owner.
std::vector<LatticeCoords> bricks_near_particles(const ParticleGrid& grid, double compact_support, double cube_edge, int threads);

// Samples the colour field of `field` at a brick's points. Particles are visited in sorted order and each point adds
// its contributions in that order: a point shared with a neighbouring brick gets the same value, bit for bit, so
// both bricks agree on which side of the surface it is. The sampler refers to `field`'s particles: they must outlive it.
BrickSampler colour_field_sampler(const SphField& field, double cube_edge, double threshold);

}  // namespace meniscus
