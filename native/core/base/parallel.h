// OpenMP helpers that never let an exception escape a parallel region: the first exception thrown by any
// iteration is captured, the remaining iterations are skipped, and it is rethrown on the calling thread.
// Reductions split the range into fixed blocks and combine them in block order, so a floating-point result has the
// same bits for any thread count.
#pragma once
#include <algorithm>
#include <atomic>
#include <cstdint>
#include <exception>
#include <mutex>
#include <vector>

#ifdef _OPENMP
#include <omp.h>
#endif

namespace meniscus {

inline int resolve_threads(int requested) {
#ifdef _OPENMP
    return requested > 0 ? requested : omp_get_max_threads();
#else
    (void)requested;
    return 1;
#endif
}

class ParallelErrors {
public:
    template <class F>
    void run(F&& body) noexcept {
        if (failed_.load(std::memory_order_relaxed)) return;
        try {
            body();
        } catch (...) {
            std::lock_guard<std::mutex> lock(mutex_);
            if (!error_) error_ = std::current_exception();
            failed_ = true;
        }
    }
    void rethrow() const {
        if (error_) std::rethrow_exception(error_);
    }

private:
    std::atomic<bool> failed_{false};
    std::mutex mutex_;
    std::exception_ptr error_;
};

// Runs body() once per thread of one OpenMP parallel region of `threads` threads (the worksharing loops in it split
// among them), or once on the calling thread, with no region, when that is one thread: GNU libgomp builds and frees
// a team for every region even of one thread, with three semaphores, which on Windows are kernel objects (under
// Wine, six round trips to its server: 0.15-0.2 ms a region, against 0.5 us on Linux; docs/performance.md).
// Worksharing loops outside a region run on the one thread, in order.
template <class F>
void parallel_region(int threads, F&& body) {
    threads = resolve_threads(threads);
    if (threads <= 1) {
        body();
        return;
    }
#pragma omp parallel num_threads(threads)
    body();
}

// Calls body(i) for i in [0, n) on `threads` threads with dynamic scheduling; in order on the calling thread when
// that is one thread or there is at most one i (no region to start: parallel_region).
template <class F>
void parallel_for(int64_t n, int threads, F&& body, int64_t chunk = 1) {
    threads = resolve_threads(threads);
    if (threads <= 1 || n <= 1) {
        for (int64_t i = 0; i < n; ++i) body(i);
        return;
    }
    ParallelErrors errors;
#pragma omp parallel for schedule(dynamic, chunk) num_threads(threads)
    for (int64_t i = 0; i < n; ++i) errors.run([&] { body(i); });
    errors.rethrow();
}

// Calls body(begin, end) for consecutive blocks of [0, n) in parallel; lets a body reuse scratch buffers for a
// whole block instead of allocating per element.
template <class F>
void parallel_blocks(int64_t n, int threads, int64_t block, F&& body) {
    if (n <= 0) return;
    const int64_t blocks = (n + block - 1) / block;
    parallel_for(blocks, threads, [&](int64_t b) { body(b * block, std::min(n, (b + 1) * block)); });
}

// Reduction over fixed blocks of [0, n): accumulate(begin, end, partial) folds one block into its own partial
// (starting from `zero`), then combine(total, partial) folds the partials into `zero` in block order. The blocks do
// not depend on the thread count, so neither does the result, bit for bit.
template <class T, class Accumulate, class Combine>
T ordered_block_reduce(int64_t n, int threads, int64_t block, const T& zero, Accumulate&& accumulate, Combine&& combine) {
    const int64_t blocks = n > 0 ? (n + block - 1) / block : 0;
    std::vector<T> partial(static_cast<std::size_t>(blocks), zero);
    parallel_for(blocks, threads, [&](int64_t b) { accumulate(b * block, std::min(n, (b + 1) * block), partial[b]); });
    T total = zero;
    for (const T& p : partial) combine(total, p);
    return total;
}

// Sum of term(i) over [0, n): each block summed in index order, the block sums added in block order.
template <class F>
double ordered_block_sum(int64_t n, int threads, int64_t block, F&& term) {
    return ordered_block_reduce(
        n, threads, block, 0.0,
        [&](int64_t begin, int64_t end, double& partial) {
            double sum = partial;  // a local: the partials of neighbouring blocks share cache lines
            for (int64_t i = begin; i < end; ++i) sum += term(i);
            partial = sum;
        },
        [](double& total, double partial) { total += partial; });
}

// Sum of the whole numbers count(i) over [0, n) (a bool counts 1 when true). Integer sums are exact in any order,
// so no fixed blocks are needed.
template <class F>
std::size_t parallel_count(int64_t n, int threads, F&& count) {
    threads = resolve_threads(threads);
    std::size_t total = 0;
    if (threads <= 1 || n <= 1) {  // no region to start (parallel_region)
        for (int64_t i = 0; i < n; ++i) total += static_cast<std::size_t>(count(i));
        return total;
    }
    ParallelErrors errors;
#pragma omp parallel for reduction(+ : total) schedule(static) num_threads(threads)
    for (int64_t i = 0; i < n; ++i) errors.run([&] { total += static_cast<std::size_t>(count(i)); });
    errors.rethrow();
    return total;
}

}  // namespace meniscus
