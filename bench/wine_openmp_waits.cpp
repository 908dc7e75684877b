// What OpenMP's synchronisation costs the Windows build under Wine against the Linux build, apart from Meniscus:
// built with g++ and with mingw-w64 (bench/wine_openmp_waits.sh), run with the same arguments:
//   wine_openmp_waits regions THREADS COUNT    COUNT empty parallel regions (libgomp builds a team for each region
//                                              of one thread; with more, it wakes the pool's sleeping threads)
//   wine_openmp_waits barriers THREADS COUNT   one region of COUNT worksharing loops, so COUNT barriers
// and prints the microseconds of each. mingw's libgomp is its POSIX port: its semaphores and mutexes are winpthreads',
// so Windows kernel objects, which Wine serves by round trips to its server process.
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <omp.h>

int main(int argc, char** argv) {
    if (argc != 4 || (std::strcmp(argv[1], "regions") != 0 && std::strcmp(argv[1], "barriers") != 0)) {
        std::fprintf(stderr, "usage: wine_openmp_waits regions|barriers THREADS COUNT\n");
        return 2;
    }
    const bool regions = std::strcmp(argv[1], "regions") == 0;
    const int threads = std::atoi(argv[2]), count = std::atoi(argv[3]);
    static volatile int sink[256];
#pragma omp parallel num_threads(threads)
    sink[omp_get_thread_num()] = 1;  // the pool's threads exist before the clock starts
    const auto start = std::chrono::steady_clock::now();
    if (regions) {
        for (int r = 0; r < count; ++r) {
#pragma omp parallel num_threads(threads)
            sink[omp_get_thread_num()] = r;
        }
    } else {
#pragma omp parallel num_threads(threads)
        for (int r = 0; r < count; ++r) {
#pragma omp for schedule(dynamic, 1)
            for (int i = 0; i < 2 * threads; ++i) sink[i] = r;
        }
    }
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    std::printf("%.1f\n", 1e6 * seconds / count);
    return 0;
}
