#include "io/frame_pattern.h"

#include <algorithm>
#include <filesystem>

#include "base/errors.h"
#include "base/platform.h"

namespace meniscus {

namespace {

bool is_digit(char c) { return c >= '0' && c <= '9'; }
bool is_letter(char c) { return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z'); }

// Where the extension starts: the longest tail of ".letter[letters/digits]*" parts (".vtk", ".bgeo.gz", ".h5"), so
// that a digit in an extension is not taken for the frame number.
std::size_t extension_start(const std::string& name) {
    std::size_t start = name.size();
    while (true) {
        const std::size_t dot = name.rfind('.', start == 0 ? 0 : start - 1);
        if (dot == std::string::npos || dot + 1 >= start || !is_letter(name[dot + 1])) return start;
        for (std::size_t i = dot + 1; i < start; ++i)
            if (!is_letter(name[i]) && !is_digit(name[i])) return start;
        start = dot;
        if (start == 0) return start;
    }
}

std::vector<std::string> folder_names(const std::string& directory) {
    std::vector<std::string> names;
    std::error_code error;
    const auto folder = path_from_utf8(directory.empty() ? "." : directory);
    for (std::filesystem::directory_iterator it(folder, error), end; !error && it != end; it.increment(error))
        names.push_back(path_to_utf8(it->path().filename()));
    return names;
}

}  // namespace

std::string FramePattern::file_name(std::int64_t frame) const {
    std::string number = std::to_string(frame);
    if (padding > 0 && frame >= 0 && static_cast<int>(number.size()) < padding)
        number.insert(0, static_cast<std::size_t>(padding) - number.size(), '0');
    return prefix + number + suffix;
}

std::string FramePattern::path(std::int64_t frame) const {
    return directory.empty() ? file_name(frame) : path_to_utf8(path_from_utf8(directory) / path_from_utf8(file_name(frame)));
}

std::string FramePattern::pattern_string() const {
    const std::string marker = padding > 0 ? std::string(static_cast<std::size_t>(padding), '#') : "{}";
    const std::string name = prefix + marker + suffix;
    return directory.empty() ? name : path_to_utf8(path_from_utf8(directory) / path_from_utf8(name));
}

std::optional<std::int64_t> FramePattern::match(const std::string& name) const {
    if (name.size() <= prefix.size() + suffix.size() || name.compare(0, prefix.size(), prefix) != 0 ||
        name.compare(name.size() - suffix.size(), suffix.size(), suffix) != 0)
        return std::nullopt;
    const std::string digits = name.substr(prefix.size(), name.size() - prefix.size() - suffix.size());
    // Frame numbers are non-negative whole numbers: a '-' belongs to the prefix ('frame-0001').
    if (digits.size() > 18) return std::nullopt;
    for (char c : digits)
        if (!is_digit(c)) return std::nullopt;
    return std::stoll(digits);
}

bool has_frame_placeholder(const std::string& path) {
    const std::string name = path_to_utf8(path_from_utf8(path).filename());
    return name.find("{}") != std::string::npos || name.find('#') != std::string::npos;
}

FramePattern parse_frame_pattern(const std::string& path, const std::optional<std::vector<std::string>>& sibling_names) {
    const auto native = path_from_utf8(path);
    const std::string name = path_to_utf8(native.filename());
    FramePattern pattern;
    pattern.directory = path_to_utf8(native.parent_path());
    if (name.empty()) throw InputError("'" + path + "' names a folder, not a file");

    const std::size_t braces = name.find("{}");
    const std::size_t hash = name.find('#');
    const std::size_t hash_end = hash == std::string::npos ? hash : name.find_first_not_of('#', hash);
    const bool second_braces = braces != std::string::npos && name.find("{}", braces + 2) != std::string::npos;
    const bool second_hashes = hash != std::string::npos && hash_end != std::string::npos && name.find('#', hash_end) != std::string::npos;
    if (second_braces || second_hashes || (braces != std::string::npos && hash != std::string::npos))
        throw InputError("'" + name + "' has more than one frame-number placeholder");
    if (braces != std::string::npos) {
        pattern.prefix = name.substr(0, braces);
        pattern.suffix = name.substr(braces + 2);
        return pattern;
    }
    if (hash != std::string::npos) {
        const std::size_t end = hash_end == std::string::npos ? name.size() : hash_end;
        pattern.prefix = name.substr(0, hash);
        pattern.suffix = name.substr(end);
        pattern.padding = static_cast<int>(end - hash);
        return pattern;
    }

    // A concrete file: the last run of digits before the extension.
    std::size_t end = extension_start(name);
    while (end > 0 && !is_digit(name[end - 1])) --end;
    if (end == 0)
        throw InputError("'" + name + "' contains no frame number (expected e.g. fluid_0001.bgeo, fluid_####.bgeo or fluid_{}.bgeo)");
    std::size_t start = end;
    while (start > 0 && is_digit(name[start - 1])) --start;
    const std::string digits = name.substr(start, end - start);
    pattern.prefix = name.substr(0, start);
    pattern.suffix = name.substr(end);
    if (digits.size() > 1 && digits[0] == '0') {
        pattern.padding = static_cast<int>(digits.size());
        return pattern;
    }
    // No leading zero: 'fluid_10' may be unpadded or padded to two digits. Only a sibling with a leading zero
    // ('fluid_01') proves padding; without one, unpadded, whose listing accepts padded names anyway.
    const std::vector<std::string> siblings = sibling_names ? *sibling_names : folder_names(pattern.directory);
    for (const std::string& sibling : siblings) {
        if (!pattern.match(sibling)) continue;
        const std::string number = sibling.substr(pattern.prefix.size(), sibling.size() - pattern.prefix.size() - pattern.suffix.size());
        if (number.size() > 1 && number[0] == '0') {
            pattern.padding = static_cast<int>(number.size());
            return pattern;
        }
    }
    return pattern;
}

FrameListing list_frames(const FramePattern& pattern) {
    struct Found {
        std::string name;
        bool exact;  // spelled with the pattern's own padding
    };
    std::map<std::int64_t, Found> found;
    std::map<std::int64_t, std::vector<std::string>> all_names;
    for (const std::string& name : folder_names(pattern.directory)) {
        const auto frame = pattern.match(name);
        if (!frame) continue;
        const bool exact = name == pattern.file_name(*frame);
        all_names[*frame].push_back(name);
        auto it = found.find(*frame);
        // The exact spelling wins; between two others the smaller name: independent of the listing order.
        if (it == found.end() || (exact && !it->second.exact) || (exact == it->second.exact && name < it->second.name))
            found[*frame] = {name, exact};
    }
    FrameListing listing;
    for (const auto& [frame, chosen] : found) {
        listing.frames[frame] = pattern.directory.empty()
                                    ? chosen.name
                                    : path_to_utf8(path_from_utf8(pattern.directory) / path_from_utf8(chosen.name));
        std::vector<std::string>& names = all_names[frame];
        if (names.size() > 1) {
            std::sort(names.begin(), names.end());
            std::string text = "frame " + std::to_string(frame) + ": ";
            for (std::size_t i = 0; i < names.size(); ++i) text += (i ? " and " : "") + names[i];
            listing.duplicates.push_back(text + "; using " + chosen.name);
        }
    }
    return listing;
}

}  // namespace meniscus
