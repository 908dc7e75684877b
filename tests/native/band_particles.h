// Particles laid out as Mantaflow's FLIP solver seeds them, for the narrow-band tests (interior fill, particle level
// set): 2 x 2 x 2 per cell, jittered a little.
#pragma once
#include <cstdint>
#include <functional>
#include <vector>

namespace meniscus {
namespace test {

// 2 x 2 x 2 particles in every cell of an n x n x n grid of `cell`-sized cells whose centre (in cells) passes `keep`,
// each coordinate jittered by up to 0.1 cell from a fixed sequence started at `seed` (deterministic).
inline std::vector<float> band_particles(int n, double cell, uint32_t seed,
                                         const std::function<bool(double, double, double)>& keep) {
    std::vector<float> out;
    uint32_t state = seed;
    const auto jitter = [&] {
        state = state * 1664525u + 1013904223u;
        return ((state >> 8) / double(1u << 24) - 0.5) * 0.2;
    };
    for (int k = 0; k < n; ++k)
        for (int j = 0; j < n; ++j)
            for (int i = 0; i < n; ++i) {
                if (!keep(i + 0.5, j + 0.5, k + 0.5)) continue;
                for (int s = 0; s < 8; ++s) {
                    const double x = i + 0.25 + 0.5 * (s & 1) + jitter(), y = j + 0.25 + 0.5 * ((s >> 1) & 1) + jitter(),
                                 z = k + 0.25 + 0.5 * (s >> 2) + jitter();
                    out.insert(out.end(), {float(x * cell), float(y * cell), float(z * cell)});
                }
            }
    return out;
}

}  // namespace test
}  // namespace meniscus
