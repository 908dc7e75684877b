#include "post/vertex_guard.h"

#include <algorithm>
#include <cmath>

namespace meniscus {

std::size_t keep_vertices_near_particles(TriMesh& mesh, const ParticleGrid& particles, double margin_length) {
    if (particles.size() == 0) return 0;
    float lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (std::size_t j = 0; j < particles.size(); ++j)
        for (int k = 0; k < 3; ++k) {
            lo[k] = std::min(lo[k], particles.position(j)[k]);
            hi[k] = std::max(hi[k], particles.position(j)[k]);
        }
    const float margin = static_cast<float>(margin_length);
    std::size_t repaired = 0;
    for (std::size_t v = 0; v < mesh.num_vertices(); ++v) {
        bool bad = false;
        for (int k = 0; k < 3; ++k) {
            float& x = mesh.vertices[3 * v + k];
            if (!std::isfinite(x) || x < lo[k] - margin || x > hi[k] + margin) {
                bad = true;
                x = std::isfinite(x) ? std::min(std::max(x, lo[k] - margin), hi[k] + margin) : 0.5f * (lo[k] + hi[k]);
            }
        }
        repaired += bad;
    }
    for (float& n : mesh.normals)
        if (!std::isfinite(n)) n = 0.0f;
    return repaired;
}

}  // namespace meniscus
