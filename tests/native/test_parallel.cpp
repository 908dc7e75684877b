// base/parallel.h: one thread runs without an OpenMP region (no team, so no semaphores: a region costs 0.15-0.2 ms
// under Wine), with the same results and errors as the parallel path.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cstdint>
#include <stdexcept>
#include <vector>

#include "base/parallel.h"

using namespace meniscus;

namespace {

bool inside_openmp_region() {
#ifdef _OPENMP
    return omp_in_parallel() != 0;
#else
    return false;
#endif
}

// The indices an orphaned worksharing loop in a parallel_region visits, in the order they were visited (a thread's
// visits are recorded under a critical section).
std::vector<int64_t> visits_of_region_loop(int threads, int64_t n, int& bodies, bool& any_inside_region) {
    std::vector<int64_t> visited;
    bodies = 0;
    any_inside_region = false;
    parallel_region(threads, [&] {
#pragma omp critical
        {
            ++bodies;
            any_inside_region = any_inside_region || inside_openmp_region();
        }
#pragma omp for schedule(dynamic, 1)
        for (int64_t i = 0; i < n; ++i) {
#pragma omp critical
            visited.push_back(i);
        }
    });
    return visited;
}

}  // namespace

TEST_CASE("one thread runs a region's body once on the calling thread, its loop in order, with no OpenMP region", "[threads]") {
    int bodies = 0;
    bool inside = true;
    const std::vector<int64_t> visited = visits_of_region_loop(1, 100, bodies, inside);
    CHECK(bodies == 1);
    CHECK_FALSE(inside);
    std::vector<int64_t> in_order(100);
    for (int64_t i = 0; i < 100; ++i) in_order[static_cast<std::size_t>(i)] = i;
    CHECK(visited == in_order);
}

#ifdef _OPENMP
TEST_CASE("two threads run a region's body on each thread and share its loop", "[threads]") {
    int bodies = 0;
    bool inside = false;
    std::vector<int64_t> visited = visits_of_region_loop(2, 100, bodies, inside);
    CHECK(bodies == 2);
    CHECK(inside);
    std::sort(visited.begin(), visited.end());
    REQUIRE(visited.size() == 100);
    for (int64_t i = 0; i < 100; ++i) CHECK(visited[static_cast<std::size_t>(i)] == i);
}
#endif

TEST_CASE("parallel_for and parallel_count give the same results on one thread as on several", "[threads]") {
    for (int threads : {1, 2, 3}) {
        std::vector<int64_t> squares(1000, -1);
        std::vector<char> inside(1000, 2);  // Catch2's CHECK is for one thread: the threads only record
        parallel_for(1000, threads, [&](int64_t i) {
            inside[static_cast<std::size_t>(i)] = inside_openmp_region();
            squares[static_cast<std::size_t>(i)] = i * i;
        });
        for (int64_t i = 0; i < 1000; ++i) CHECK(squares[static_cast<std::size_t>(i)] == i * i);
#ifdef _OPENMP
        CHECK(std::count(inside.begin(), inside.end(), threads > 1 ? 1 : 0) == 1000);
#endif
        CHECK(parallel_count(1000, threads, [](int64_t i) { return i % 3 == 0; }) == 334);
        CHECK(ordered_block_sum(1000, threads, 64, [](int64_t i) { return 0.1 * static_cast<double>(i); }) ==
              ordered_block_sum(1000, 1, 64, [](int64_t i) { return 0.1 * static_cast<double>(i); }));
    }
}

TEST_CASE("on one thread parallel_for stops at the first error and rethrows it", "[threads]") {
    std::vector<int64_t> ran;
    CHECK_THROWS_WITH(parallel_for(10, 1,
                                   [&](int64_t i) {
                                       ran.push_back(i);
                                       if (i == 3) throw std::runtime_error("item 3 failed");
                                   }),
                      "item 3 failed");
    CHECK(ran == std::vector<int64_t>{0, 1, 2, 3});
    CHECK_THROWS_WITH(parallel_for(10, 2, [](int64_t i) { if (i == 7) throw std::runtime_error("item 7 failed"); }), "item 7 failed");
}
