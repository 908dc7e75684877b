// Memory accounting: the machine's memory, this process's peak, and the budget check run before large
// allocations so that a mistaken parameter is refused with an estimate instead of exhausting the machine.
#pragma once
#include <cstddef>
#include <string>

namespace meniscus {

std::size_t physical_memory_bytes();
std::size_t peak_rss_bytes();                       // high-water mark of this process (0 where unknown)
std::size_t default_memory_budget_bytes();          // 75 % of physical memory
std::string format_bytes(double bytes);             // "1.5 GiB"

// Throws ResourceError naming `what` and the estimate when estimate_bytes exceeds the budget
// (budget 0 means the default budget).
void check_memory_budget(double estimate_bytes, std::size_t budget_bytes, const std::string& what);

}  // namespace meniscus
