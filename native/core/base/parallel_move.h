// memmove in parallel: a long run of elements shifted by a short distance (a few rows inserted or dropped in a list
// of millions), which a single memmove does on one thread.
#pragma once
#include <algorithm>
#include <cstdint>
#include <cstring>
#include <type_traits>
#include <vector>

#include "base/parallel.h"

namespace meniscus {

constexpr int64_t kMoveChunk = int64_t{1} << 16;

// Moves data[from, from + count) to data[to, to + count), the ranges may overlap. Fixed chunks of the source move at
// once; where a chunk's destination covers the neighbouring chunk's source (the `distance` elements at the chunk's
// end when moving down, at its start when moving up), that neighbour's part is saved first and written from the copy.
template <class T>
void move_in_parallel(T* data, int64_t from, int64_t to, int64_t count, int threads) {
    static_assert(std::is_trivially_copyable<T>::value, "moved with memmove");
    const int64_t distance = to > from ? to - from : from - to;
    if (distance == 0 || count <= 0) return;
    // A chunk's destination reaches at most its neighbour's source (chunk >= distance), and the saved parts, one
    // distance per chunk, stay within a sixteenth of the moved run: a long shift moves in fewer, longer chunks.
    const int64_t chunk = std::max(kMoveChunk, 16 * distance);
    if (count < 2 * chunk) {
        std::memmove(data + to, data + from, static_cast<std::size_t>(count) * sizeof(T));
        return;
    }
    const int64_t chunks = (count + chunk - 1) / chunk;
    const bool down = to < from;
    // Moving down, chunk c + 1 overwrites the last `distance` source elements of chunk c; moving up, chunk c - 1
    // overwrites the first `distance` of chunk c. Those are the saved parts (each min(distance, chunk length)).
    auto bounds = [&](int64_t c) { return std::make_pair(c * chunk, std::min(count, (c + 1) * chunk)); };
    auto saved_range = [&](int64_t c) {
        const auto b = bounds(c);
        const bool needed = down ? c + 1 < chunks : c > 0;
        const int64_t length = needed ? std::min(distance, b.second - b.first) : 0;
        return down ? std::make_pair(b.second - length, b.second) : std::make_pair(b.first, b.first + length);
    };
    std::vector<T> saved(static_cast<std::size_t>(chunks * distance));
    parallel_for(chunks, threads, [&](int64_t c) {
        const auto s = saved_range(c);
        std::copy(data + from + s.first, data + from + s.second, saved.data() + c * distance);
    });
    parallel_for(chunks, threads, [&](int64_t c) {
        const auto b = bounds(c);
        const auto s = saved_range(c);
        const T* copy = saved.data() + c * distance;
        // The part not saved moves directly (memmove: it may overlap itself), then the saved part from its copy.
        const int64_t direct_first = down ? b.first : s.second, direct_last = down ? s.first : b.second;
        if (direct_last > direct_first)
            std::memmove(data + to + direct_first, data + from + direct_first, static_cast<std::size_t>(direct_last - direct_first) * sizeof(T));
        std::copy(copy, copy + (s.second - s.first), data + to + s.first);
    });
}

}  // namespace meniscus
