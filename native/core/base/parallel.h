// OpenMP helpers that never let an exception escape a parallel region: the first exception thrown by any
// iteration is captured, the remaining iterations are skipped, and it is rethrown on the calling thread.
#pragma once
#include <atomic>
#include <cstdint>
#include <exception>
#include <mutex>

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

// Calls body(i) for i in [0, n) on `threads` threads with dynamic scheduling.
template <class F>
void parallel_for(int64_t n, int threads, F&& body, int64_t chunk = 1) {
    ParallelErrors errors;
#pragma omp parallel for schedule(dynamic, chunk) num_threads(resolve_threads(threads))
    for (int64_t i = 0; i < n; ++i) errors.run([&] { body(i); });
    errors.rethrow();
}

}  // namespace meniscus
