// Particle data as read from a file: positions plus every point attribute the file carries.
#pragma once
#include <cstddef>
#include <optional>
#include <vector>

#include "base/attributes.h"
#include "sph/fluid_domain.h"

namespace meniscus {

struct ParticleData {
    std::vector<float> positions;        // 3 * count, x y z interleaved
    std::vector<Attribute> attributes;   // each with count() == size(); integer fields (ids) converted to float
    std::optional<FluidDomain> fluid_domain;  // set by readers of grid solvers' caches (Mantaflow), else empty

    std::size_t size() const { return positions.size() / 3; }
};

// A read-only view of (N,3) C-contiguous positions in float or double, so callers (numpy) need not copy.
struct PositionsView {
    const float* f32 = nullptr;
    const double* f64 = nullptr;
    std::size_t count = 0;

    PositionsView() = default;
    PositionsView(const float* data, std::size_t n) : f32(data), count(n) {}
    PositionsView(const double* data, std::size_t n) : f64(data), count(n) {}
    double coord(std::size_t i, int k) const { return f32 ? double(f32[3 * i + k]) : f64[3 * i + k]; }
};

}  // namespace meniscus
