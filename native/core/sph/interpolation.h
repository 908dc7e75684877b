// SPH sums at arbitrary points (paper Eq. 7 and Sec. 4): per-particle values interpolated onto mesh vertices with
// the Shepard correction, whole-number values taken from the nearest particle, and colour-field normals. Queries
// reuse the particle grid the reconstruction built; points are processed in blocks of consecutive points, which
// share their neighbour cells (mesh vertices come in spatially coherent order).
#pragma once
#include <vector>

#include "base/attributes.h"
#include "sph/kernel.h"
#include "sph/neighborhood.h"

namespace meniscus {

// A frame's particles as an SPH field: the sorted grid, the kernel and every particle's volume V_j (sorted order).
// A view of what the reconstruction owns.
struct SphField {
    const ParticleGrid& grid;
    const std::vector<float>& volumes;
    CubicSplineKernel kernel;
};

// Shepard-corrected SPH interpolation (Eq. 7) of per-particle values (in the caller's original particle order,
// `components` floats each, 1 to 16) at the given points: sum_j V_j W_j A_j / sum_j V_j W_j; points without any
// particle within the support get 0. out has points * components floats.
void interpolate_at_points(const SphField& field, const float* particle_values, int components, const std::vector<float>& points,
                           std::vector<float>& out, int threads);

// The same for values given per sorted particle (as the densities' neighbour counts are).
void interpolate_sorted_at_points(const SphField& field, const float* sorted_values, int components, const std::vector<float>& points,
                                  std::vector<float>& out, int threads);

// Each point takes the values of its nearest particle within the support (the first in sorted order on a tie;
// 0 where there is none): the transfer for whole-number attributes (particle ids, phase or emitter labels, flags),
// whose averages would mean nothing.
void nearest_particle_at_points(const SphField& field, const float* particle_values, int components, const std::vector<float>& points,
                                std::vector<float>& out, int threads);

// Throws InputError naming an attribute without data for `particle_count` particles or without 1 to 16 components.
void validate_attribute_inputs(const std::vector<AttributeInput>& attributes, std::size_t particle_count);

// Every attribute carried onto the points: integral ones from the nearest particle, the others interpolated.
std::vector<Attribute> transfer_attributes(const SphField& field, const std::vector<AttributeInput>& attributes,
                                           const std::vector<float>& points, int threads);

// Outward unit normals from the colour-field gradient (SPH normals) at the given points.
std::vector<float> colour_field_normals(const SphField& field, const std::vector<float>& points, int threads);

}  // namespace meniscus
