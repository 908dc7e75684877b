// Deterministic parallel greedy selection of disjoint vertex sets: the sets a serial pass in index order takes
// (a set is taken when none of its vertices belongs to a set taken before it), whatever the thread count.
#pragma once
#include <atomic>
#include <cstdint>
#include <limits>
#include <vector>

#include "base/parallel.h"

namespace meniscus {

// Which of `regions` (vertex indices < claim.size(), repeats allowed) the serial greedy pass takes, found in
// parallel rounds: an undecided region whose index is the smallest among the undecided ones on each of its vertices
// has no undecided predecessor it meets and none taken (it would have been dropped), so the serial pass takes it; an
// undecided region meeting a taken one is dropped, as the serial pass drops it. Each round decides at least the
// smallest undecided region; on meshes the chains of conflicts are short, so there are few rounds. The taken
// regions' vertices get claim[v] = mark (no vertex may hold `mark` before); `lowest` (claim.size() entries) is
// scratch, written before it is read (so it need not be initialised). Returns taken[i] for every region. Claims and
// Lowest: any vectors of int32_t and of std::atomic<int32_t> (with any allocator).
template <class Claims, class Lowest>
std::vector<uint8_t> select_greedy_disjoint(const std::vector<std::vector<int32_t>>& regions, Claims& claim, int32_t mark, Lowest& lowest,
                                            int threads) {
    enum : uint8_t { kUndecided, kTaken, kDropped };
    std::vector<uint8_t> state(regions.size(), kUndecided);
    std::vector<int32_t> undecided(regions.size());
    for (std::size_t i = 0; i < regions.size(); ++i) undecided[i] = static_cast<int32_t>(i);
    while (!undecided.empty()) {
        auto for_undecided = [&](auto&& body) {
            parallel_for(static_cast<int64_t>(undecided.size()), threads, [&](int64_t k) { body(undecided[static_cast<std::size_t>(k)]); }, 16);
        };
        for_undecided([&](int32_t i) {
            for (int32_t v : regions[i]) lowest[v].store(std::numeric_limits<int32_t>::max(), std::memory_order_relaxed);
        });
        for_undecided([&](int32_t i) {
            for (int32_t v : regions[i]) {
                int32_t seen = lowest[v].load(std::memory_order_relaxed);
                while (i < seen && !lowest[v].compare_exchange_weak(seen, i, std::memory_order_relaxed)) {
                }
            }
        });
        for_undecided([&](int32_t i) {
            bool smallest = true;
            for (int32_t v : regions[i]) smallest = smallest && lowest[v].load(std::memory_order_relaxed) == i;
            if (smallest) state[i] = kTaken;
        });
        for_undecided([&](int32_t i) {  // regions taken in one round are disjoint: one writer per vertex
            if (state[i] == kTaken)
                for (int32_t v : regions[i]) claim[v] = mark;
        });
        for_undecided([&](int32_t i) {
            if (state[i] != kUndecided) return;
            for (int32_t v : regions[i])
                if (claim[v] == mark) {
                    state[i] = kDropped;
                    return;
                }
        });
        std::size_t still = 0;
        for (int32_t i : undecided)
            if (state[i] == kUndecided) undecided[still++] = i;
        undecided.resize(still);
    }
    for (uint8_t& s : state) s = s == kTaken ? 1 : 0;
    return state;
}

}  // namespace meniscus
