#include "post/weights.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <map>
#include <mutex>

#include "base/numbers.h"
#include "base/parallel.h"
#include "sph/kernel.h"

namespace meniscus {

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
namespace {

constexpr int kProfileSamples = 801;  // samples of u in [-1, 1]
constexpr int kDepths = 800;          // particle depths z' in [-2, 0]: deeper particles do not reach the surface region

// P_f sampled at kProfileSamples points of [-1, 1], each by the trapezoidal rule.
template <class Radial>
std::vector<double> plane_profile(Radial&& f) {
    std::vector<double> values(kProfileSamples);
    for (int i = 0; i < kProfileSamples; ++i) {
        const double u = -1.0 + 2.0 * i / (kProfileSamples - 1);
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
}

// A sampled profile at u, linearly interpolated; 0 outside (-1, 1).
double profile_at(const std::vector<double>& p, double u) {
    if (u <= -1.0 || u >= 1.0) return 0.0;
    const double x = (u + 1.0) * 0.5 * (kProfileSamples - 1);
    const int i = std::min(static_cast<int>(x), kProfileSamples - 2);
    const double f = x - i;
    return p[i] * (1.0 - f) + p[i + 1] * f;
}

// int_{max(z,-1)}^1 p(u) du
double profile_tail(const std::vector<double>& p, double z) {
    const int steps = 800;
    const double a = std::max(z, -1.0);
    if (a >= 1.0) return 0.0;
    const double h = (1.0 - a) / steps;
    double sum = 0.0;
    for (int k = 0; k <= steps; ++k) sum += (k == 0 || k == steps ? 0.5 : 1.0) * profile_at(p, a + k * h);
    return sum * h;
}

// The continuum half-space of the derivation above, discretised in particle depth.
class HalfSpaceModel {
public:
    HalfSpaceModel()
        : kernel_profile_(plane_profile(CubicSplineKernel::unit_value)),
          hat_profile_(plane_profile([](double s) { return 1.0 - s; })),
          depth_(kDepths), fraction_(kDepths), count_(kDepths) {
        for (int i = 0; i < kDepths; ++i) {
            depth_[i] = -2.0 + 2.0 * (i + 0.5) / kDepths;
            fraction_[i] = profile_tail(kernel_profile_, depth_[i]);
            count_[i] = profile_tail(hat_profile_, depth_[i]);
        }
    }

    // phi(z); with interpolated_count, also N(z) / n.
    double colour_field(double z, double* interpolated_count) const {
        const double dz = 2.0 / kDepths;
        double phi = 0.0, weighted = 0.0;
        for (int i = 0; i < kDepths; ++i) {
            const double w = profile_at(kernel_profile_, z - depth_[i]) / fraction_[i] * dz;
            phi += w;
            weighted += w * count_[i];
        }
        if (interpolated_count) *interpolated_count = phi > 0.0 ? weighted / phi : 0.0;
        return phi;
    }

    // z_s with phi(z_s) = t: phi decreases with height through the surface, so bisect on [-1, 1].
    double surface_height(double iso_threshold) const {
        double lo = -1.0, hi = 1.0;
        for (int it = 0; it < 60; ++it) {
            const double mid = 0.5 * (lo + hi);
            (colour_field(mid, nullptr) > iso_threshold ? lo : hi) = mid;
        }
        return 0.5 * (lo + hi);
    }

private:
    std::vector<double> kernel_profile_, hat_profile_;
    std::vector<double> depth_, fraction_, count_;  // per depth: z', F(z'), C(z')
};

}  // namespace

double flat_surface_count_ratio(double iso_threshold) {
    static std::mutex mutex;
    static std::map<double, double> cache;
    std::lock_guard<std::mutex> lock(mutex);
    const auto cached = cache.find(iso_threshold);
    if (cached != cache.end()) return cached->second;
    const HalfSpaceModel model;
    double surface_count = 0.0;
    model.colour_field(model.surface_height(iso_threshold), &surface_count);
    const double ratio = surface_count / (kPi / 3.0);
    cache[iso_threshold] = ratio;
    return ratio;
}

namespace {

// Order-preserving unsigned key of a float (negative values flipped whole, positive ones with the sign bit set).
inline uint32_t order_key(float value) {
    uint32_t bits;
    std::memcpy(&bits, &value, sizeof bits);
    return (bits & 0x80000000u) ? ~bits : (bits | 0x80000000u);
}

constexpr int64_t kSelectBlock = int64_t{1} << 16;
constexpr int kBucketBits = 16;

// The k-th smallest (0-based) of the values that take(value) accepts (k < their count), the value std::nth_element
// finds, in two parallel passes instead of a serial partition of a copy: the taken values are counted per bucket of
// their key's high bits (fixed blocks, integer counts: the same at any thread count), the bucket holding rank k is
// found, and only its values are gathered and partitioned.
template <class Take>
float kth_smallest(const std::vector<float>& values, std::size_t k, int threads, Take&& take) {
    const int64_t n = static_cast<int64_t>(values.size());
    const int64_t blocks = (n + kSelectBlock - 1) / kSelectBlock;
    const std::size_t buckets = std::size_t{1} << kBucketBits;
    auto bucket_of = [](float v) { return order_key(v) >> (32 - kBucketBits); };
    // Per block: counts per bucket, and per group of 256 buckets, so that the search reads few counts.
    // (Made here rather than by the worker threads, whose allocations would land in their own malloc arenas.)
    std::vector<std::vector<uint32_t>> block_counts(static_cast<std::size_t>(blocks), std::vector<uint32_t>(buckets)),
        group_counts(static_cast<std::size_t>(blocks), std::vector<uint32_t>(buckets >> 8));
    parallel_for(blocks, threads, [&](int64_t b) {
        std::vector<uint32_t>& count = block_counts[static_cast<std::size_t>(b)];
        std::vector<uint32_t>& group = group_counts[static_cast<std::size_t>(b)];
        for (int64_t i = b * kSelectBlock, end = std::min(n, i + kSelectBlock); i < end; ++i)
            if (take(values[i])) {
                const uint32_t bucket = bucket_of(values[i]);
                ++count[bucket], ++group[bucket >> 8];
            }
    });
    // The first bucket whose values and those of the buckets before it number more than k (k < their total).
    std::size_t below = 0;
    auto step = [&](const std::vector<std::vector<uint32_t>>& counts, std::size_t first, std::size_t last) {
        for (std::size_t i = first; i < last; ++i) {
            std::size_t in = 0;
            for (const auto& c : counts) in += c[i];
            if (below + in > k || i + 1 == last) return i;
            below += in;
        }
        return last - 1;
    };
    const std::size_t group = step(group_counts, 0, buckets >> 8);
    const std::size_t bucket = step(block_counts, group << 8, (group + 1) << 8);
    std::vector<std::vector<float>> block_members(static_cast<std::size_t>(blocks));
    parallel_for(blocks, threads, [&](int64_t b) {
        if (block_counts[static_cast<std::size_t>(b)][bucket] == 0) return;
        for (int64_t i = b * kSelectBlock, end = std::min(n, i + kSelectBlock); i < end; ++i)
            if (take(values[i]) && bucket_of(values[i]) == bucket) block_members[static_cast<std::size_t>(b)].push_back(values[i]);
    });
    std::vector<float> members;
    for (const auto& m : block_members) members.insert(members.end(), m.begin(), m.end());
    const std::size_t rank = k - below;
    std::nth_element(members.begin(), members.begin() + static_cast<std::ptrdiff_t>(rank), members.end());
    return members[rank];
}

}  // namespace

double bulk_neighbor_count(const std::vector<float>& neighbor_counts, int threads) {
    if (neighbor_counts.empty()) return 0.0;
    // The 95th percentile sits among the fully surrounded particles unless the frame is almost all spray; the
    // median of the particles within 25 % of it is the bulk value, robust against a few over-packed outliers.
    const std::size_t p95 = static_cast<std::size_t>(0.95 * double(neighbor_counts.size() - 1));
    const float high = kth_smallest(neighbor_counts, p95, threads, [](float) { return true; });
    const float low = 0.75f * high;
    auto in_bulk = [low](float c) { return c >= low; };
    const std::size_t bulk = parallel_count(static_cast<int64_t>(neighbor_counts.size()), threads,
                                            [&](int64_t i) { return in_bulk(neighbor_counts[i]); });
    return bulk == 0 ? high : kth_smallest(neighbor_counts, bulk / 2, threads, in_bulk);
}

double halfspace_normalization(const std::vector<float>& neighbor_counts, double iso_threshold, double requested, int threads) {
    if (requested > 0.0) return requested;
    const double value = flat_surface_count_ratio(iso_threshold) * bulk_neighbor_count(neighbor_counts, threads);
    return value > 0.0 ? value : 1.0;
}

std::vector<float> feature_weights(const SphField& field, const std::vector<float>& neighbor_counts, const std::vector<float>& points,
                                   double normalization, bool smoothstep, int threads) {
    std::vector<float> weights;
    interpolate_sorted_at_points(field, neighbor_counts.data(), 1, points, weights, threads);
    const float inverse = static_cast<float>(1.0 / normalization);
    parallel_blocks(static_cast<int64_t>(weights.size()), threads, kSelectBlock, [&](int64_t begin, int64_t end) {
        for (int64_t i = begin; i < end; ++i) {
            float x = std::min(std::max(weights[i] * inverse, 0.0f), 1.0f);  // Eq. 8 (min, not max)
            if (smoothstep) x = x * x * x * (x * (6.0f * x - 15.0f) + 10.0f);  // Eq. 9
            weights[i] = x;
        }
    });
    return weights;
}

}  // namespace meniscus
