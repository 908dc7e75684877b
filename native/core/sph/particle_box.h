// Particles kept by a box (splashsurf's --particle-aabb-min/max and convert's --domain-min/max): those outside are
// dropped with their attribute values, the rest keep their order.
#pragma once
#include <cstddef>

#include "parameters.h"
#include "sph/particles.h"

namespace meniscus {

// Drops the particles outside [min, max] (bounds included) and returns how many were dropped.
std::size_t keep_particles_in_box(ParticleData& particles, const Vector3& min, const Vector3& max);

}  // namespace meniscus
