// The axis-aligned bounding box of 3 floats per point, for the stages that need one of millions of vertices or
// particles: a serial sweep of a 1 M-particle frame's mesh takes ~10 ms, which many threads then wait for.
#pragma once
#include <algorithm>
#include <cmath>
#include <cstdint>

#include "base/parallel.h"

namespace meniscus {

struct FloatBox {
    float lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
};

// In fixed blocks folded in order: the serial loop's bits (std::min and std::max keep the first of equal values, so
// even which of +0 and -0 ends in the box does not depend on the threads). NaN coordinates are skipped.
inline FloatBox bounding_box(const float* xyz, int64_t points, int threads) {
    return ordered_block_reduce(
        points, threads, int64_t{1} << 16, FloatBox{},
        [&](int64_t begin, int64_t end, FloatBox& box) {
            for (int64_t i = begin; i < end; ++i)
                for (int d = 0; d < 3; ++d) box.lo[d] = std::min(box.lo[d], xyz[3 * i + d]), box.hi[d] = std::max(box.hi[d], xyz[3 * i + d]);
        },
        [](FloatBox& total, const FloatBox& box) {
            for (int d = 0; d < 3; ++d) total.lo[d] = std::min(total.lo[d], box.lo[d]), total.hi[d] = std::max(total.hi[d], box.hi[d]);
        });
}

}  // namespace meniscus
