// Order-keeping compaction in parallel: the items of [0, n) that a predicate keeps, numbered in index order as a
// serial loop numbers them. Fixed blocks (counted in parallel, a scan over the block counts, numbered in parallel), so
// the numbers do not depend on the thread count. keep(i) is called twice per item and must give the same answer.
#pragma once
#include <cstdint>
#include <vector>

#include "base/parallel.h"

namespace meniscus {

constexpr int64_t kCompactionBlock = int64_t{1} << 16;

namespace compaction_detail {

// first[b] = how many items of the blocks before b are kept; first[blocks] = all kept.
template <class Keep>
std::vector<int64_t> kept_before_blocks(int64_t n, int threads, Keep& keep) {
    const int64_t blocks = n > 0 ? (n + kCompactionBlock - 1) / kCompactionBlock : 0;
    std::vector<int64_t> first(static_cast<std::size_t>(blocks) + 1, 0);
    parallel_for(blocks, threads, [&](int64_t b) {
        int64_t count = 0;
        for (int64_t i = b * kCompactionBlock, end = std::min(n, i + kCompactionBlock); i < end; ++i) count += keep(i) ? 1 : 0;
        first[static_cast<std::size_t>(b) + 1] = count;
    });
    for (std::size_t b = 1; b < first.size(); ++b) first[b] += first[b - 1];
    return first;
}

}  // namespace compaction_detail

// new_index[i] = the rank of i among the kept items, -1 for the others (new_index holds n entries); returns the
// number kept.
template <class Keep>
int64_t number_kept(int64_t n, int threads, Keep&& keep, int32_t* new_index) {
    const std::vector<int64_t> first = compaction_detail::kept_before_blocks(n, threads, keep);
    parallel_for(static_cast<int64_t>(first.size()) - 1, threads, [&](int64_t b) {
        int64_t next = first[static_cast<std::size_t>(b)];
        for (int64_t i = b * kCompactionBlock, end = std::min(n, i + kCompactionBlock); i < end; ++i)
            new_index[i] = keep(i) ? static_cast<int32_t>(next++) : -1;
    });
    return first.back();
}

// The kept items of [0, n), ascending, as Index (uint32_t where n may pass INT32_MAX).
template <class Index = int32_t, class Keep>
std::vector<Index> kept_indices(int64_t n, int threads, Keep&& keep) {
    const std::vector<int64_t> first = compaction_detail::kept_before_blocks(n, threads, keep);
    std::vector<Index> out(static_cast<std::size_t>(first.back()));
    parallel_for(static_cast<int64_t>(first.size()) - 1, threads, [&](int64_t b) {
        int64_t next = first[static_cast<std::size_t>(b)];
        for (int64_t i = b * kCompactionBlock, end = std::min(n, i + kCompactionBlock); i < end; ++i)
            if (keep(i)) out[static_cast<std::size_t>(next++)] = static_cast<Index>(i);
    });
    return out;
}

}  // namespace meniscus
