// Grid-index coordinates of a fluid domain (sph/fluid_domain.h) and back: the narrow-band fill classifies the
// solver's cells in them, the particle level set (surface/particle_level_set.h) samples its refined grid in them.
#pragma once
#include <array>

#include "sph/fluid_domain.h"

namespace meniscus {

using Vec3 = std::array<double, 3>;
using Mat3 = std::array<Vec3, 3>;  // rows

// Grid-index coordinates of world points: the inverse of world = origin + sum_a g[a] * axes[a].
struct GridMap {
    Vec3 origin{};
    Mat3 to_world{};  // to_world[r][a] = axes[a][r]
    Mat3 to_grid{};

    explicit GridMap(const FluidDomain& d) : origin(d.origin) {
        for (int r = 0; r < 3; ++r)
            for (int a = 0; a < 3; ++a) to_world[r][a] = d.axes[a][r];
        const Mat3& m = to_world;
        const double det = m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1]) - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0]) +
                           m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0]);
        for (int r = 0; r < 3; ++r)
            for (int c = 0; c < 3; ++c) {
                // Inverse by cofactors: (adj m)[r][c] = cofactor of m[c][r].
                const int r1 = (c + 1) % 3, r2 = (c + 2) % 3, c1 = (r + 1) % 3, c2 = (r + 2) % 3;
                to_grid[r][c] = (m[r1][c1] * m[r2][c2] - m[r1][c2] * m[r2][c1]) / det;
            }
    }
    Vec3 grid(const Vec3& world) const {
        const Vec3 d{world[0] - origin[0], world[1] - origin[1], world[2] - origin[2]};
        Vec3 g{};
        for (int r = 0; r < 3; ++r) g[r] = to_grid[r][0] * d[0] + to_grid[r][1] * d[1] + to_grid[r][2] * d[2];
        return g;
    }
    Vec3 direction(const Vec3& world) const {
        Vec3 g{};
        for (int r = 0; r < 3; ++r) g[r] = to_grid[r][0] * world[0] + to_grid[r][1] * world[1] + to_grid[r][2] * world[2];
        return g;
    }
    Vec3 world(const Vec3& g) const {
        Vec3 w = origin;
        for (int r = 0; r < 3; ++r) w[r] += to_world[r][0] * g[0] + to_world[r][1] * g[1] + to_world[r][2] * g[2];
        return w;
    }
};

}  // namespace meniscus
