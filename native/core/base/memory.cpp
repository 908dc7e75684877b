#include "base/memory.h"

#include <cstdio>

#include "base/errors.h"

namespace meniscus {

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
