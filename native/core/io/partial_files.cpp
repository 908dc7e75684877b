#include "io/partial_files.h"

#include <chrono>
#include <filesystem>
#include <system_error>

#include "base/platform.h"

namespace fs = std::filesystem;

namespace meniscus {

namespace {

// The process id in text[begin, end) when it is all digits (a sane length); -1 otherwise.
long parse_process_id(const std::string& text, std::size_t begin, std::size_t end) {
    if (end <= begin || end - begin > 10) return -1;
    long id = 0;
    for (std::size_t i = begin; i < end; ++i) {
        if (text[i] < '0' || text[i] > '9') return -1;
        id = id * 10 + (text[i] - '0');
    }
    return id;
}

}  // namespace

std::string partial_path(const std::string& target, long process_id) {
    const fs::path path = path_from_utf8(target);
    const std::string name = path_to_utf8(path.filename());
    const std::size_t dot = name.rfind('.');
    const bool has_extension = dot != std::string::npos && dot > 0;
    const std::string stem = has_extension ? name.substr(0, dot) : name;
    const std::string extension = has_extension ? name.substr(dot) : ".partial";
    return path_to_utf8(path.parent_path() / path_from_utf8(stem + ".partial" + std::to_string(process_id) + extension));
}

std::string hidden_partial_path(const std::string& target, long process_id) {
    const fs::path path = path_from_utf8(target);
    return path_to_utf8(path.parent_path() /
                        path_from_utf8(".partial-" + std::to_string(process_id) + "-" + path_to_utf8(path.filename())));
}

long partial_writer(const std::string& name) {
    static const std::string marker = ".partial";
    if (name.rfind(marker + "-", 0) == 0) {  // the command line's ".partial-<id>-<name>"
        const std::size_t dash = name.find('-', marker.size() + 1);
        if (dash == std::string::npos || dash + 1 >= name.size()) return -1;
        return parse_process_id(name, marker.size() + 1, dash);
    }
    // "<stem>.partial<id>.<extension>": the last marker, digits, then one extension without dots.
    const std::size_t at = name.rfind(marker);
    if (at == std::string::npos || at == 0) return -1;
    const std::size_t dot = name.find('.', at + marker.size());
    if (dot == std::string::npos || dot + 1 >= name.size() || name.find('.', dot + 1) != std::string::npos) return -1;
    return parse_process_id(name, at + marker.size(), dot);
}

std::vector<std::string> remove_abandoned_partials(const std::string& folder, double abandoned_after_seconds) {
    std::vector<std::string> removed;
    std::error_code error;
    const auto now = fs::file_time_type::clock::now();
    for (fs::directory_iterator it(path_from_utf8(folder), error); !error && it != fs::directory_iterator(); it.increment(error)) {
        const fs::directory_entry& entry = *it;
        const std::string name = path_to_utf8(entry.path().filename());
        const long writer = partial_writer(name);
        std::error_code entry_error;  // a file gone meanwhile is skipped; the listing goes on
        if (writer < 0 || process_exists(writer) || !entry.is_regular_file(entry_error)) continue;
        const auto modified = entry.last_write_time(entry_error);
        if (entry_error) continue;
        const double age = std::chrono::duration<double>(now - modified).count();
        if (age <= abandoned_after_seconds) continue;
        if (fs::remove(entry.path(), entry_error)) removed.push_back(name);
    }
    return removed;
}

}  // namespace meniscus
