// Particles kept by a box (splashsurf's --particle-aabb-min/max and convert's --domain-min/max): those outside are
// dropped with their attribute values, the rest keep their order.
#pragma once
#include <cstddef>

#include "parameters.h"
#include "sph/particles.h"

namespace meniscus {

// Inside [lower, upper], bounds included (NaN is outside). The one rule of both boxes' particle filters.
inline bool inside_box(const double point[3], const Vector3& lower, const Vector3& upper) {
    return point[0] >= lower[0] && point[0] <= upper[0] && point[1] >= lower[1] && point[1] <= upper[1] &&
           point[2] >= lower[2] && point[2] <= upper[2];
}

// Drops the particles outside [min, max] (bounds included) and returns how many were dropped.
std::size_t keep_particles_in_box(ParticleData& particles, const Vector3& min, const Vector3& max);

}  // namespace meniscus
