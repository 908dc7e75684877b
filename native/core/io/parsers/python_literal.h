// Python literals as repr() writes them, the part of the syntax the NumPy .npy header uses: dicts, tuples, lists,
// quoted strings, integers (with Python 2's 'L'), True, False and None. Nothing is evaluated.
#pragma once
#include <cstdint>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "io/io_util.h"

namespace meniscus {
namespace io_detail {

struct PyValue {
    enum class Kind { none, boolean, integer, string, sequence, dict } kind = Kind::none;
    bool boolean = false;
    std::int64_t integer = 0;
    std::string string;
    std::vector<PyValue> items;                            // tuple or list
    std::vector<std::pair<std::string, PyValue>> entries;  // dict, in order

    // The dict entry under `key`, or nullptr.
    const PyValue* get(std::string_view key) const;
};

// Parses `text`, which starts at byte `base` of the cursor's source, as one literal. Errors read
// "<context> at byte N: what", e.g. "bad .npy header at byte 17: a string is not closed".
PyValue parse_python_literal(const Cursor& c, std::string_view text, std::size_t base, const std::string& context);

}  // namespace io_detail
}  // namespace meniscus
