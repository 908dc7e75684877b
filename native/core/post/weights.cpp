#include "post/weights.h"

#include <algorithm>
#include <cmath>
#include <mutex>
#include <map>

#include "base/numbers.h"
#include "base/parallel.h"

namespace meniscus {

namespace {

// Cubic-spline shape with H = 1, normalised to unit integral.
double kernel_unit(double q) {
    const double norm = 8.0 / kPi;
    if (q <= 0.5) return norm * (1.0 - 6.0 * q * q + 6.0 * q * q * q);
    if (q < 1.0) return norm * 2.0 * (1.0 - q) * (1.0 - q) * (1.0 - q);
    return 0.0;
}

}  // namespace

// Derivation of the automatic N_HS (the paper leaves it open, splashsurf hard-codes 13).
// Model the fluid as a continuum of particles with number density n filling the half-space z < 0, lengths in
// units of H. Integrating a radial function f over planes gives the profile P_f(u) = 2 pi int_|u|^1 f(s) s ds, and
//   - the particle number density estimated by SPH at depth z is n F(z), F(z) = int_{max(z,-1)}^1 P_W(u) du,
//     so the particle volume is V(z) = 1 / (n F(z));
//   - the hat-weighted count (Eq. 11) of a particle at depth z is n C(z), C(z) = int_{max(z,-1)}^1 P_hat(u) du,
//     which is n pi / 3 deep inside;
//   - the colour field (Eq. 1) at height z is phi(z) = int P_W(z - z') / F(z') dz' (n cancels), and the surface
//     lies where phi(z_s) = t;
//   - the interpolated count there (Eq. 7) is N(z_s) = n int P_W(z_s - z') C(z') / F(z') dz' / phi(z_s).
// The ratio N(z_s) / (n pi / 3) depends only on the kernel shape and t (0.66 for t = 0.6), not on n, r or H.
// Multiplying it by the frame's own bulk count (measured, so that it follows compression) gives N_HS.
double flat_surface_count_ratio(double iso_threshold) {
    static std::mutex mutex;
    static std::map<double, double> cache;
    std::lock_guard<std::mutex> lock(mutex);
    const auto cached = cache.find(iso_threshold);
    if (cached != cache.end()) return cached->second;

    constexpr int kProfile = 801;  // samples of u in [-1, 1]
    auto profile = [&](auto&& f) {
        std::vector<double> values(kProfile);
        for (int i = 0; i < kProfile; ++i) {
            const double u = -1.0 + 2.0 * i / (kProfile - 1);
            const int steps = 400;
            const double a = std::fabs(u), h = (1.0 - a) / steps;
            double sum = 0.0;
            for (int k = 0; k <= steps; ++k) {
                const double s = a + k * h;
                sum += (k == 0 || k == steps ? 0.5 : 1.0) * f(s) * s;
            }
            values[i] = 2.0 * kPi * sum * h;
        }
        return values;
    };
    const std::vector<double> p_kernel = profile(kernel_unit);
    const std::vector<double> p_hat = profile([](double s) { return 1.0 - s; });
    auto profile_at = [&](const std::vector<double>& p, double u) {
        if (u <= -1.0 || u >= 1.0) return 0.0;
        const double x = (u + 1.0) * 0.5 * (kProfile - 1);
        const int i = std::min(static_cast<int>(x), kProfile - 2);
        const double f = x - i;
        return p[i] * (1.0 - f) + p[i + 1] * f;
    };
    auto tail = [&](const std::vector<double>& p, double z) {  // int_{max(z,-1)}^1 p(u) du
        const int steps = 800;
        const double a = std::max(z, -1.0);
        if (a >= 1.0) return 0.0;
        const double h = (1.0 - a) / steps;
        double sum = 0.0;
        for (int k = 0; k <= steps; ++k) sum += (k == 0 || k == steps ? 0.5 : 1.0) * profile_at(p, a + k * h);
        return sum * h;
    };
    // Particle depths z' in [-2, 0]: deeper particles do not reach the surface region.
    constexpr int kDepths = 800;
    std::vector<double> depth(kDepths), fraction(kDepths), count(kDepths);
    for (int i = 0; i < kDepths; ++i) {
        depth[i] = -2.0 + 2.0 * (i + 0.5) / kDepths;
        fraction[i] = tail(p_kernel, depth[i]);
        count[i] = tail(p_hat, depth[i]);
    }
    const double dz = 2.0 / kDepths;
    auto field = [&](double z, double* interpolated_count) {
        double phi = 0.0, weighted = 0.0;
        for (int i = 0; i < kDepths; ++i) {
            const double w = profile_at(p_kernel, z - depth[i]) / fraction[i] * dz;
            phi += w;
            weighted += w * count[i];
        }
        if (interpolated_count) *interpolated_count = phi > 0.0 ? weighted / phi : 0.0;
        return phi;
    };
    // phi decreases with height through the surface: bisect for phi(z_s) = t on [-1, 1].
    double lo = -1.0, hi = 1.0;
    for (int it = 0; it < 60; ++it) {
        const double mid = 0.5 * (lo + hi);
        (field(mid, nullptr) > iso_threshold ? lo : hi) = mid;
    }
    double surface_count = 0.0;
    field(0.5 * (lo + hi), &surface_count);
    const double ratio = surface_count / (kPi / 3.0);
    cache[iso_threshold] = ratio;
    return ratio;
}

double bulk_neighbor_count(const SurfaceReconstruction& r) {
    std::vector<float> counts = r.neighbor_counts;
    if (counts.empty()) return 0.0;
    // The 95th percentile sits among the fully surrounded particles unless the frame is almost all spray; the
    // median of the particles within 25 % of it is the bulk value, robust against a few over-packed outliers.
    const std::size_t p95 = static_cast<std::size_t>(0.95 * double(counts.size() - 1));
    std::nth_element(counts.begin(), counts.begin() + static_cast<std::ptrdiff_t>(p95), counts.end());
    const float high = counts[p95];
    std::vector<float> bulk;
    for (float c : r.neighbor_counts)
        if (c >= 0.75f * high) bulk.push_back(c);
    const std::size_t mid = bulk.size() / 2;
    std::nth_element(bulk.begin(), bulk.begin() + static_cast<std::ptrdiff_t>(mid), bulk.end());
    return bulk[mid];
}

double halfspace_normalization(const SurfaceReconstruction& r, double requested) {
    if (requested > 0.0) return requested;
    const double value = flat_surface_count_ratio(r.params.iso_threshold) * bulk_neighbor_count(r);
    // Degenerate frames (a few isolated particles) have no bulk: any positive value gives them weight 0 anyway.
    return value > 0.0 ? value : 1.0;
}

std::vector<float> feature_weights(const SurfaceReconstruction& r, const std::vector<float>& points, double normalization, bool smoothstep,
                                   int threads) {
    std::vector<float> weights;
    interpolate_sorted_at_points(r, r.neighbor_counts.data(), 1, points, weights, threads);
    const float inverse = static_cast<float>(1.0 / normalization);
    for (float& w : weights) {
        float x = std::min(std::max(w * inverse, 0.0f), 1.0f);  // Eq. 8 (min, not max)
        if (smoothstep) x = x * x * x * (x * (6.0f * x - 15.0f) + 10.0f);  // Eq. 9
        w = x;
    }
    return weights;
}

}  // namespace meniscus
