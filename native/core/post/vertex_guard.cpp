#include "post/vertex_guard.h"

#include <algorithm>
#include <cmath>

#include "base/bounding_box.h"
#include "base/parallel.h"

namespace meniscus {

std::size_t keep_vertices_near_particles(TriMesh& mesh, const ParticleGrid& particles, double margin_length, int threads) {
    if (particles.size() == 0) return 0;
    const FloatBox box = bounding_box(particles.positions().data(), static_cast<int64_t>(particles.size()), threads);
    const float margin = static_cast<float>(margin_length);
    const std::size_t repaired = parallel_count(static_cast<int64_t>(mesh.num_vertices()), threads, [&](int64_t v) {
        bool bad = false;
        for (int k = 0; k < 3; ++k) {
            float& x = mesh.vertices[3 * v + k];
            if (!std::isfinite(x) || x < box.lo[k] - margin || x > box.hi[k] + margin) {
                bad = true;
                x = std::isfinite(x) ? std::min(std::max(x, box.lo[k] - margin), box.hi[k] + margin) : 0.5f * (box.lo[k] + box.hi[k]);
            }
        }
        return bad;
    });
    parallel_blocks(static_cast<int64_t>(mesh.normals.size()), threads, int64_t{1} << 16, [&](int64_t begin, int64_t end) {
        for (int64_t k = begin; k < end; ++k)
            if (!std::isfinite(mesh.normals[k])) mesh.normals[k] = 0.0f;
    });
    return repaired;
}

}  // namespace meniscus
