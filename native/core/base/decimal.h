// Decimal text <-> floating point, always in the C format ('.' as the decimal point) whatever locale the host
// process has set (Blender may set one that writes decimal commas). std::from_chars / std::to_chars where the
// standard library has them for floating point (libstdc++, MSVC); otherwise (libc++ before LLVM 17, which macOS
// ships) strtof / snprintf under a per-thread C locale.
#pragma once
#include <cstddef>
#include <string_view>
#include <system_error>

namespace meniscus {

struct DecimalResult {
    const char* end;  // one past the last character used
    std::errc error;  // std::errc() on success; result_out_of_range when the value does not fit (out is not set)
};

// As std::from_chars(first, last, out) with chars_format::general: no leading blanks or '+', inf and nan accepted.
DecimalResult parse_decimal(const char* first, const char* last, double& out);
DecimalResult parse_decimal(const char* first, const char* last, float& out);

// The shortest text that reads back as the same float (at most 9 significant digits where the library has no
// shortest formatting); writes at most 32 characters and returns one past the last.
char* format_decimal(char* first, float value);
// The same for a double (at most 17 significant digits without shortest formatting).
char* format_decimal(char* first, double value);

}  // namespace meniscus
