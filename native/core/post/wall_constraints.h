// Vertices held on a container's walls. Where the surface meets a wall of the mesh box (--mesh-aabb-min/max with
// clamping), its vertices lie exactly on the wall's plane; every stage that moves vertices afterwards (smoothing,
// volume restoration, any new smoothing) calls apply() after each step, so such a vertex keeps its coordinate along
// the wall's normal: it slides along the wall, never off it. An empty mask means no walls (the usual case).
#pragma once
#include <array>
#include <cstddef>
#include <cstdint>
#include <vector>

namespace meniscus {

struct WallConstraints {
    // Per vertex: bit f set when the vertex lies on box face f (0: min x, 1: max x, 2: min y, 3: max y, 4: min z,
    // 5: max z). Empty: no walls.
    std::vector<uint8_t> mask;
    std::array<float, 6> planes{};  // the faces' coordinates, in the same order

    bool empty() const { return mask.empty(); }

    // Resets the constrained coordinate of every vertex on a wall (positions: 3 floats per vertex).
    void apply(float* positions, std::size_t vertex_count) const {
        if (mask.empty()) return;
        for (std::size_t v = 0; v < vertex_count && v < mask.size(); ++v) {
            const uint8_t faces = mask[v];
            if (faces == 0) continue;
            for (int f = 0; f < 6; ++f)
                if (faces & (1u << f)) positions[3 * v + f / 2] = planes[static_cast<std::size_t>(f)];
        }
    }
};

}  // namespace meniscus
