// How threads wait at OpenMP barriers and for work: briefly spinning, then sleeping.
#pragma once
#include <cstdlib>

#ifdef _OPENMP
#include <omp.h>
#if defined(__GNUC__) && !defined(__clang__) && !defined(KMP_VERSION_MAJOR)
#define MENISCUS_LIBGOMP 1  // GCC's own runtime (LLVM's omp.h defines KMP_VERSION_MAJOR)
#endif
#endif

namespace meniscus {

// How long a thread that waits spins before it sleeps. The runtimes' defaults (libgomp 300 000 spins, LLVM 200 ms)
// cost nothing on an idle machine, but beside another busy program a spinning thread holds the core the thread it
// waits for needs: a frame of many short parallel regions took 6.8x its idle time beside a second OpenMP program.
// Fully passive waiting cost the idle frame ~18 %; a spin of some microseconds keeps the short waits of an idle run
// cheap and lets the long ones sleep. libgomp reads GOMP_SPINCOUNT once, when it loads (the CLI sets it and
// restarts itself, native/cli/main.cpp; the Python package sets it before its module loads); LLVM's runtime takes
// its block time at run time: wait_briefly_at_barriers(). A policy the user set (OMP_WAIT_POLICY, GOMP_SPINCOUNT,
// KMP_BLOCKTIME) is left as it is.
inline constexpr const char* kBarrierSpinCount = "10000";
inline constexpr int kBarrierBlockMilliseconds = 1;

inline void wait_briefly_at_barriers() {
#if defined(_OPENMP) && defined(KMP_VERSION_MAJOR)
    if (!std::getenv("KMP_BLOCKTIME") && !std::getenv("OMP_WAIT_POLICY")) kmp_set_blocktime(kBarrierBlockMilliseconds);
#endif
}

}  // namespace meniscus
