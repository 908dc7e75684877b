// Cubic-spline SPH kernel with compact support H (splashsurf's convention: H = 2 * l * r):
// W(d) = 8 / (pi H^3) * { 1 - 6q^2 + 6q^3 for q <= 1/2;  2 (1 - q)^3 for 1/2 < q <= 1;  0 beyond },  q = d / H.
// One function in three spellings, each where its rounding is relied on: shape() with a branch per piece,
// shape_branch_free() for the particle loops that vectorise, unit_value() in double for the continuum model of the
// feature weights. They agree to rounding; the pinned output depends on each call site keeping its spelling.
#pragma once
#include <algorithm>
#include <cmath>

#include "base/numbers.h"

namespace meniscus {

class CubicSplineKernel {
public:
    explicit CubicSplineKernel(double compact_support)
        : support_(static_cast<float>(compact_support)),
          support_squared_(static_cast<float>(compact_support * compact_support)),
          inverse_support_(static_cast<float>(1.0 / compact_support)),
          normalisation_(static_cast<float>(8.0 / (kPi * compact_support * compact_support * compact_support))) {}

    float support() const { return support_; }
    float support_squared() const { return support_squared_; }

    // W as a function of the distance d (0 <= d).
    float value(float distance) const { return normalisation_ * shape(distance * inverse_support_); }

    // dW/dd (<= 0), for gradients: grad W(x - x_j) = dW/dd * (x - x_j) / d.
    float derivative(float distance) const {
        const float q = distance * inverse_support_;
        float s;
        if (q <= 0.5f) s = q * (-12.0f + 18.0f * q);
        else if (q < 1.0f) { const float a = 1.0f - q; s = -6.0f * a * a; }
        else s = 0.0f;
        return normalisation_ * inverse_support_ * s;
    }

    // W / W(0) at q = d / H.
    static float shape(float q) {
        if (q <= 0.5f) return 1.0f + q * q * (-6.0f + 6.0f * q);
        if (q < 1.0f) { const float a = 1.0f - q; return 2.0f * a * a * a; }
        return 0.0f;
    }

    // The same as 2 a^3 - b^3 with a = max(1 - q, 0) and b = max(1 - 2q, 0): exact on all of [0, 1] and 0 beyond,
    // without a branch, so that neighbour loops over particles vectorise.
    static float shape_branch_free(float q) {
        const float a = std::max(1.0f - q, 0.0f), b = std::max(1.0f - 2.0f * q, 0.0f);
        return 2.0f * a * a * a - b * b * b;
    }

    // W for H = 1 (normalised to unit integral), in double.
    static double unit_value(double q) {
        const double norm = 8.0 / kPi;
        if (q <= 0.5) return norm * (1.0 - 6.0 * q * q + 6.0 * q * q * q);
        if (q < 1.0) return norm * 2.0 * (1.0 - q) * (1.0 - q) * (1.0 - q);
        return 0.0;
    }

private:
    float support_, support_squared_, inverse_support_, normalisation_;
};

}  // namespace meniscus
