// Memory accounting: the budget check run before large allocations, so that a mistaken parameter is refused with
// an estimate instead of exhausting the machine. (The machine's memory and this process's peak: base/platform.h.)
#pragma once
#include <cstddef>
#include <string>

#include "base/platform.h"

namespace meniscus {

std::size_t default_memory_budget_bytes();          // 75 % of physical memory
std::string format_bytes(double bytes);             // "1.5 GiB"

// Throws ResourceError naming `what` and the estimate when estimate_bytes exceeds the budget
// (budget 0 means the default budget).
void check_memory_budget(double estimate_bytes, std::size_t budget_bytes, const std::string& what);

}  // namespace meniscus
