// Feature weights of the paper (Sec. 3.2): the hat-weighted neighbour counts of the particles (Eq. 10-11, computed
// during the reconstruction's density pass) are interpolated to the mesh vertices with a Shepard-corrected SPH sum
// (Eq. 7), normalised by the half-space count N_HS and clamped to [0, 1] (Eq. 8, with min), and optionally pushed
// to the extremes by a smoothstep (Eq. 9).
#pragma once
#include <vector>

#include "parameters.h"
#include "surface/reconstruction.h"

namespace meniscus {

// Ratio between the interpolated count at a flat free surface and the count of a particle deep inside the fluid,
// for the cubic-spline kernel, the hat function with h = H and the given iso threshold (see weights.cpp).
double flat_surface_count_ratio(double iso_threshold);

// Bulk (full-neighbourhood) hat-weighted count of this frame's particles: a robust high-end statistic of the
// per-particle counts, so that it follows the frame's own packing (compressed or expanded fluids).
double bulk_neighbor_count(const SurfaceReconstruction& reconstruction);

// N_HS: the given value when > 0, otherwise derived automatically from the kernel, the threshold and the data.
double halfspace_normalization(const SurfaceReconstruction& reconstruction, double requested);

// Weight lambda_i in [0, 1] for each point (3 floats each). Points with no particle in reach get 0.
std::vector<float> feature_weights(const SurfaceReconstruction& reconstruction, const std::vector<float>& points,
                                   double normalization, bool smoothstep, int threads);

}  // namespace meniscus
