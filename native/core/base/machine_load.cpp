#include "base/machine_load.h"

#include <algorithm>
#include <chrono>
#include <climits>
#include <cstdio>
#include <cstdlib>

#include "base/parallel.h"

#ifdef __linux__
#include <dirent.h>
#include <sched.h>
#include <unistd.h>

#include <cstring>
#endif

namespace meniscus {

namespace {

#ifdef __linux__
// A few samples, a short gap apart: the fewest counts, so that a thread that ran for a moment (a kernel worker, the
// host's own wake-up) takes no core away; programs that hold cores show in every sample. The first sample that finds
// this thread alone settles it (a quiet machine: one read, microseconds); a busy one ~0.45 ms per frame. The
// gaps are waited out awake: a thread that sleeps on a busy machine waits for a core to wake on (0.9 ms a frame).
constexpr int kSamples = 4;
constexpr auto kSampleGap = std::chrono::microseconds(100);

// Threads running or ready to run on the machine now (the fourth field of /proc/loadavg: running/total), this one
// among them; -1 when it cannot be read. Parsed by hand: the first three fields are decimals in the C locale, and a
// host program (Blender) may have set another one.
int running_threads_now() {
    std::FILE* file = std::fopen("/proc/loadavg", "r");
    if (!file) return -1;
    char text[256];
    const std::size_t length = std::fread(text, 1, sizeof text - 1, file);
    std::fclose(file);
    text[length] = '\0';
    const char* p = text;
    for (int field = 0; field < 3; ++field) {
        while (*p == ' ') ++p;
        while (*p && *p != ' ') ++p;
    }
    char* end = nullptr;
    const long running = std::strtol(p, &end, 10);
    return end != p && *end == '/' && running > 0 && running < INT_MAX ? static_cast<int>(running) : -1;
}
#endif

}  // namespace

#ifdef __linux__
int own_running_threads() {
    DIR* tasks = opendir("/proc/self/task");
    if (!tasks) return 0;
    int running = 0;
    while (const dirent* task = readdir(tasks)) {
        if (task->d_name[0] < '0' || task->d_name[0] > '9') continue;
        char path[64];
        std::snprintf(path, sizeof path, "/proc/self/task/%.20s/stat", task->d_name);
        std::FILE* file = std::fopen(path, "r");
        if (!file) continue;  // a thread that ended meanwhile
        char text[512];
        const std::size_t length = std::fread(text, 1, sizeof text - 1, file);
        std::fclose(file);
        text[length] = '\0';
        // "tid (name) S ...": the name may hold spaces and parentheses, so the state follows the last ')'.
        const char* close = std::strrchr(text, ')');
        if (close && close[1] == ' ' && close[2] == 'R') ++running;
    }
    closedir(tasks);
    return running;
}
#else
int own_running_threads() { return 0; }
#endif

int free_cores(int most, int usable, int online, int busy_elsewhere) {
    most = std::max(1, most);
    if (usable <= 0 || online <= 0 || busy_elsewhere <= 0) return most;
    // Pinned to some of the machine's cores, only their share of the others' threads falls on them.
    const long long busy_here = static_cast<long long>(busy_elsewhere) * std::min(usable, online) / online;
    return static_cast<int>(std::max<long long>(1, std::min<long long>(most, usable - busy_here)));
}

int automatic_frame_threads() {
    const int most = resolve_threads(0);
#ifdef __linux__
    if (most <= 1) return 1;
    cpu_set_t mask;
    const int usable = sched_getaffinity(0, sizeof mask, &mask) == 0 ? CPU_COUNT(&mask) : most;
    const long online = sysconf(_SC_NPROCESSORS_ONLN);
    int fewest = INT_MAX;
    for (int sample = 0; sample < kSamples; ++sample) {
        if (sample > 0)
            for (const auto until = std::chrono::steady_clock::now() + kSampleGap; std::chrono::steady_clock::now() < until;) {
            }
        const int running = running_threads_now();
        if (running <= 1) return most;  // unreadable, or nothing else runs
        const int elsewhere = running - std::max(1, own_running_threads());
        if (elsewhere <= 0) return most;  // only this process's threads run
        fewest = std::min(fewest, elsewhere);
    }
    return free_cores(most, usable, online > 0 && online < INT_MAX ? static_cast<int>(online) : usable, fewest);
#else
    return most;
#endif
}

}  // namespace meniscus
