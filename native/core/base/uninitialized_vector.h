// A vector whose resize leaves new elements of trivial types unwritten, for large arrays that a parallel loop fills
// completely afterwards. std::vector's resize writes every new element (zeros) on the calling thread, and on a
// fresh allocation that first write also takes the page faults, so each ~50 MB array cost ~15-30 ms of serial time
// at a million particles before any parallel work began (most of what stopped decimation and the particle grid from
// scaling). With this allocator the parallel fill is the first touch, so the page faults happen on all threads.
// Elements with arguments (push_back, assign, insert, copies) are constructed as by std::allocator.
#pragma once
#include <algorithm>
#include <cstdint>
#include <memory>
#include <new>
#include <type_traits>
#include <utility>
#include <vector>

#include "base/parallel.h"

namespace meniscus {

template <class T>
class DefaultInitAllocator {
public:
    using value_type = T;
    // Stateless, like std::allocator: a moved vector hands its buffer over (libc++ would otherwise move element by
    // element, which std::atomic elements cannot).
    using propagate_on_container_move_assignment = std::true_type;
    using is_always_equal = std::true_type;
    template <class U>
    struct rebind {
        using other = DefaultInitAllocator<U>;
    };

    DefaultInitAllocator() noexcept = default;
    template <class U>
    DefaultInitAllocator(const DefaultInitAllocator<U>&) noexcept {}

    T* allocate(std::size_t n) { return std::allocator<T>().allocate(n); }
    void deallocate(T* p, std::size_t n) noexcept { std::allocator<T>().deallocate(p, n); }

    // No arguments: default-initialised (nothing written for trivial types).
    template <class U>
    void construct(U* p) noexcept(std::is_nothrow_default_constructible<U>::value) {
        ::new (static_cast<void*>(p)) U;
    }
    template <class U, class... Args>
    void construct(U* p, Args&&... args) {
        ::new (static_cast<void*>(p)) U(std::forward<Args>(args)...);
    }
    template <class U>
    void destroy(U* p) noexcept {
        p->~U();
    }
};

template <class T, class U>
bool operator==(const DefaultInitAllocator<T>&, const DefaultInitAllocator<U>&) noexcept {
    return true;
}
template <class T, class U>
bool operator!=(const DefaultInitAllocator<T>&, const DefaultInitAllocator<U>&) noexcept {
    return false;
}

template <class T>
using UninitializedVector = std::vector<T, DefaultInitAllocator<T>>;

// Block size of the helpers below: large enough that a block's pages are its own, small enough to spread the work.
constexpr int64_t kFirstTouchBlock = int64_t{1} << 16;

// out resized to n elements, every one set to `value`, written in parallel blocks (the first touch of its pages).
template <class T>
void fill_in_parallel(UninitializedVector<T>& out, std::size_t n, const T& value, int threads) {
    out.resize(n);
    parallel_blocks(static_cast<int64_t>(n), threads, kFirstTouchBlock,
                    [&](int64_t begin, int64_t end) { std::fill(out.data() + begin, out.data() + end, value); });
}

// out resized to n elements copied from `from`, in parallel blocks.
template <class T>
void copy_in_parallel(const T* from, std::size_t n, UninitializedVector<T>& out, int threads) {
    out.resize(n);
    parallel_blocks(static_cast<int64_t>(n), threads, kFirstTouchBlock,
                    [&](int64_t begin, int64_t end) { std::copy(from + begin, from + end, out.data() + begin); });
}

}  // namespace meniscus
