#include "memory.h"

#include <cstdio>
#include <sys/resource.h>
#include <unistd.h>

#include "errors.h"

namespace meniscus {

std::size_t physical_memory_bytes() {
    long pages = sysconf(_SC_PHYS_PAGES);
    long page_size = sysconf(_SC_PAGE_SIZE);
    if (pages <= 0 || page_size <= 0) return std::size_t(8) << 30;  // unknown: assume a modest 8 GiB
    return static_cast<std::size_t>(pages) * static_cast<std::size_t>(page_size);
}

std::size_t peak_rss_bytes() {
    struct rusage usage {};
    if (getrusage(RUSAGE_SELF, &usage) != 0) return 0;
    return static_cast<std::size_t>(usage.ru_maxrss) * 1024;  // Linux reports KiB
}

std::size_t default_memory_budget_bytes() { return physical_memory_bytes() / 4 * 3; }

std::string format_bytes(double bytes) {
    const char* units[] = {"B", "KiB", "MiB", "GiB", "TiB", "PiB"};
    int unit = 0;
    while (bytes >= 1024.0 && unit < 5) {
        bytes /= 1024.0;
        ++unit;
    }
    char buffer[64];
    std::snprintf(buffer, sizeof buffer, "%.1f %s", bytes, units[unit]);
    return buffer;
}

void check_memory_budget(double estimate_bytes, std::size_t budget_bytes, const std::string& what) {
    const std::size_t budget = budget_bytes ? budget_bytes : default_memory_budget_bytes();
    if (estimate_bytes > static_cast<double>(budget))
        throw ResourceError(what + " would need about " + format_bytes(estimate_bytes) + ", more than the memory budget of " +
                            format_bytes(static_cast<double>(budget)) +
                            "; use a larger cube size or raise the budget (memory_budget)");
}

}  // namespace meniscus
