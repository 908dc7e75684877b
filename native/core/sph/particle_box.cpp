#include "sph/particle_box.h"

#include <vector>

namespace meniscus {

std::size_t keep_particles_in_box(ParticleData& particles, const Vector3& min, const Vector3& max) {
    const std::size_t n = particles.size();
    std::vector<std::size_t> kept;
    kept.reserve(n);
    for (std::size_t i = 0; i < n; ++i) {
        const double point[3] = {particles.positions[3 * i], particles.positions[3 * i + 1], particles.positions[3 * i + 2]};
        if (inside_box(point, min, max)) kept.push_back(i);
    }
    if (kept.size() == n) return 0;
    auto gather = [&kept](std::vector<float>& values, std::size_t components) {
        std::vector<float> out;
        out.reserve(kept.size() * components);
        for (std::size_t i : kept) out.insert(out.end(), &values[i * components], &values[i * components] + components);
        values.swap(out);
    };
    gather(particles.positions, 3);
    for (Attribute& attribute : particles.attributes) gather(attribute.values, static_cast<std::size_t>(attribute.components));
    return n - kept.size();
}

}  // namespace meniscus
