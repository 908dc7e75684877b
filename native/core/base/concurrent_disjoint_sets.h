// Disjoint sets that several threads unite at once. A root is only ever hooked under a smaller root (by a
// compare-and-swap, retried when another thread moved it first), so every set ends with its smallest element as its
// root, whatever the order of the unions: the result does not depend on the thread count. Paths are halved on the
// way (a non-root's parent only ever moves to one of its ancestors, so racing halvings stay valid).
#pragma once
#include <atomic>
#include <cstdint>
#include <memory>
#include <utility>
#include <vector>

#include "base/parallel.h"

namespace meniscus {

class ConcurrentDisjointSets {
public:
    // The parents are first written by the threads (a vector of atomics would zero them all on this one first).
    ConcurrentDisjointSets(std::size_t n, int threads) : parent_(new std::atomic<int32_t>[n]) {
        parallel_blocks(static_cast<int64_t>(n), threads, int64_t{1} << 16, [&](int64_t begin, int64_t end) {
            for (int64_t i = begin; i < end; ++i) parent_[i].store(static_cast<int32_t>(i), std::memory_order_relaxed);
        });
    }

    int32_t find(int32_t v) {
        while (true) {
            int32_t p = parent_[v].load(std::memory_order_relaxed);
            if (p == v) return v;
            const int32_t grandparent = parent_[p].load(std::memory_order_relaxed);
            if (grandparent != p) parent_[v].compare_exchange_weak(p, grandparent, std::memory_order_relaxed);
            v = grandparent;
        }
    }

    void unite(int32_t a, int32_t b) {
        while (true) {
            a = find(a);
            b = find(b);
            if (a == b) return;
            if (a < b) std::swap(a, b);  // hook the larger root under the smaller
            int32_t expected = a;
            if (parent_[a].compare_exchange_strong(expected, b, std::memory_order_relaxed)) return;
        }
    }

private:
    std::unique_ptr<std::atomic<int32_t>[]> parent_;
};

}  // namespace meniscus
