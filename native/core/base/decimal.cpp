#include "base/decimal.h"

#include <cerrno>
#include <charconv>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <string>

#if !(defined(__cpp_lib_to_chars) && __cpp_lib_to_chars >= 201611L)
#define MENISCUS_DECIMAL_FROM_C_LIBRARY 1
#include <locale.h>
#if defined(__APPLE__)
#include <xlocale.h>
#endif
#endif

namespace meniscus {

#ifndef MENISCUS_DECIMAL_FROM_C_LIBRARY

DecimalResult parse_decimal(const char* first, const char* last, double& out) {
    const auto r = std::from_chars(first, last, out);
    return {r.ptr, r.ec};
}

DecimalResult parse_decimal(const char* first, const char* last, float& out) {
    const auto r = std::from_chars(first, last, out);
    return {r.ptr, r.ec};
}

char* format_decimal(char* first, float value) { return std::to_chars(first, first + 32, value).ptr; }

char* format_decimal(char* first, double value) { return std::to_chars(first, first + 32, value).ptr; }

#else

namespace {

// The thread uses the C locale while this lives (uselocale is per thread: other threads are not affected).
class CLocaleScope {
public:
    CLocaleScope() : previous_(uselocale(c_locale())) {}
    ~CLocaleScope() { uselocale(previous_); }
    CLocaleScope(const CLocaleScope&) = delete;
    CLocaleScope& operator=(const CLocaleScope&) = delete;

private:
    static locale_t c_locale() {
        static const locale_t locale = newlocale(LC_ALL_MASK, "C", static_cast<locale_t>(0));
        return locale;
    }
    locale_t previous_;
};

template <class T, class Convert>
DecimalResult parse_with(const char* first, const char* last, T& out, Convert convert) {
    // from_chars accepts neither leading blanks, a sign '+', nor hexadecimal: refuse what strtod would take beyond it.
    if (first == last || *first == ' ' || *first == '\t' || *first == '\n' || *first == '\r' || *first == '+')
        return {first, std::errc::invalid_argument};
    const std::string text(first, last);  // strtod needs a terminated string
    const std::size_t digits = text[0] == '-' ? 1 : 0;
    if (text.size() > digits + 1 && text[digits] == '0' && (text[digits + 1] == 'x' || text[digits + 1] == 'X'))
        return {first + digits + 1, std::errc()};  // from_chars stops after the 0
    CLocaleScope c_locale;
    char* end = nullptr;
    errno = 0;
    const T value = convert(text.c_str(), &end);
    if (end == text.c_str()) return {first, std::errc::invalid_argument};
    const char* stop = first + (end - text.c_str());
    // strto* report ERANGE for subnormal results too; from_chars only for values beyond the range or lost to 0.
    if (errno == ERANGE && (value == 0 || value == std::numeric_limits<T>::infinity() || value == -std::numeric_limits<T>::infinity()))
        return {stop, std::errc::result_out_of_range};
    out = value;
    return {stop, std::errc()};
}

}  // namespace

DecimalResult parse_decimal(const char* first, const char* last, double& out) {
    return parse_with(first, last, out, [](const char* s, char** end) { return std::strtod(s, end); });
}

DecimalResult parse_decimal(const char* first, const char* last, float& out) {
    return parse_with(first, last, out, [](const char* s, char** end) { return std::strtof(s, end); });
}

char* format_decimal(char* first, float value) {
    CLocaleScope c_locale;
    // 9 significant digits always read back as the same float; fewer where they already do.
    for (int digits = 6; digits <= 9; ++digits) {
        const int n = std::snprintf(first, 32, "%.*g", digits, static_cast<double>(value));
        if (std::strtof(first, nullptr) == value || digits == 9 || value != value) return first + n;
    }
    return first;
}

char* format_decimal(char* first, double value) {
    CLocaleScope c_locale;
    for (int digits = 15; digits <= 17; ++digits) {
        const int n = std::snprintf(first, 32, "%.*g", digits, value);
        if (std::strtod(first, nullptr) == value || digits == 17 || value != value) return first + n;
    }
    return first;
}

#endif

}  // namespace meniscus
