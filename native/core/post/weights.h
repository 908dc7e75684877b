// Feature weights of the paper (Sec. 3.2): the hat-weighted neighbour counts of the particles (Eq. 10-11, measured
// by the density pass, sph/density.h) are interpolated to the mesh vertices with a Shepard-corrected SPH sum
// (Eq. 7), normalised by the half-space count N_HS and clamped to [0, 1] (Eq. 8, with min), and optionally pushed
// to the extremes by a smoothstep (Eq. 9). Weight ~1 on flat, well-supported surface; ~0 on droplets and thin sheets.
#pragma once
#include <vector>

#include "sph/interpolation.h"

namespace meniscus {

// Ratio between the interpolated count at a flat free surface and the count of a particle deep inside the fluid,
// for the cubic-spline kernel, the hat function with h = H and the given iso threshold (see weights.cpp).
double flat_surface_count_ratio(double iso_threshold);

// Bulk (full-neighbourhood) hat-weighted count of a frame's particles: a robust high-end statistic of the
// per-particle counts, so that it follows the frame's own packing (compressed or expanded fluids). 0 without particles.
double bulk_neighbor_count(const std::vector<float>& neighbor_counts, int threads);

// N_HS: `requested` when > 0, otherwise flat_surface_count_ratio(iso_threshold) times the bulk count (1 when that
// is not positive: a frame without bulk gets weight 0 everywhere anyway).
double halfspace_normalization(const std::vector<float>& neighbor_counts, double iso_threshold, double requested, int threads);

// Weight lambda_i in [0, 1] for each point (3 floats each), from the particles' neighbour counts (sorted order, as
// the densities hold them). Points with no particle in reach get 0.
std::vector<float> feature_weights(const SphField& field, const std::vector<float>& neighbor_counts, const std::vector<float>& points,
                                   double normalization, bool smoothstep, int threads);

}  // namespace meniscus
