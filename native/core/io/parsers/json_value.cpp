// The JSON value tree, selections, the memory budget and the container builder shared by both JSON parsers.
#include <cmath>

#include "io/parsers/json.h"

namespace meniscus {
namespace io_detail {

// ---- values --------------------------------------------------------------------------------------------------

std::uint64_t JsonValue::size() const {
    switch (kind) {
        case Kind::array: return items.size();
        case Kind::numbers: return numbers.size();
        case Kind::matrix: return width ? numbers.size() / width : 0;
        case Kind::uniform:
        case Kind::bits: return count;
        default: return 0;
    }
}

double JsonValue::at(std::uint64_t i) const {
    if (kind == Kind::numbers) return numbers[static_cast<std::size_t>(i)];
    if (kind == Kind::uniform) return decode_scalar(data + i * scalar_size(type), type, big_endian);
    if (kind == Kind::bits) {  // packed booleans: bit i % 32 of 32-bit word i / 32
        const unsigned char* w = data + 4 * (i / 32);
        return ((big_endian ? load_be32(w) : load_le32(w)) >> (i % 32)) & 1u;
    }
    const JsonValue& v = items[static_cast<std::size_t>(i)];
    return v.kind == Kind::number || v.kind == Kind::boolean ? v.number : std::nan("");
}

std::uint64_t JsonValue::rows() const {
    if (kind == Kind::matrix) return size();
    if (kind != Kind::array) return 0;
    for (const auto& v : items)
        if (!v.is_sequence() || !v.all_numeric()) return 0;
    return items.size();
}

std::uint64_t JsonValue::row_size(std::uint64_t i) const { return kind == Kind::matrix ? width : items[static_cast<std::size_t>(i)].size(); }

double JsonValue::cell(std::uint64_t i, std::uint64_t j) const {
    return kind == Kind::matrix ? numbers[static_cast<std::size_t>(i * width + j)] : items[static_cast<std::size_t>(i)].at(j);
}

bool JsonValue::all_numeric() const {
    if (kind == Kind::numbers || kind == Kind::uniform || kind == Kind::bits) return true;
    if (kind != Kind::array) return false;
    for (const auto& v : items)
        if (v.kind != Kind::number && v.kind != Kind::boolean) return false;
    return true;
}

const JsonValue* json_lookup(const JsonValue& v, std::string_view key) {
    if (v.kind == JsonValue::Kind::map) {
        for (std::size_t i = 0; i < v.keys.size(); ++i)
            if (v.keys[i] == key) return &v.items[i];
        return nullptr;
    }
    if (v.kind != JsonValue::Kind::array) return nullptr;
    for (std::size_t i = 0; i + 1 < v.items.size(); i += 2)
        if (v.items[i].kind == JsonValue::Kind::string && v.items[i].text == key) return &v.items[i + 1];
    return nullptr;
}

// ---- selections and budget -----------------------------------------------------------------------------------

const JsonSelection* JsonSelection::everything() {
    static const JsonSelection all;
    return &all;
}

JsonSelection& JsonSelection::keep(std::string key, const JsonSelection* below) {
    keys_.emplace_back(std::move(key), below);
    return *this;
}

const JsonSelection* JsonSelection::child(const JsonSelection* level, bool keyed, std::string_view key) {
    if (!level || level == everything() || !keyed) return level;
    for (const auto& entry : level->keys_)
        if (entry.first == key) return entry.second;
    return nullptr;
}

void JsonBudget::take(std::uint64_t bytes) {
    if (bytes > left_)
        c_.fail("the JSON structure needs more memory than a geometry file of this size justifies (corrupt, or not "
                "particle data)");
    left_ -= bytes;
}

// ---- containers ----------------------------------------------------------------------------------------------

const JsonSelection* JsonContainerBuilder::child_selection(std::string_view key) const {
    return JsonSelection::child(level_, is_map_ || after_key_, is_map_ ? key : std::string_view(pending_key_));
}

void JsonContainerBuilder::add(std::string&& key, JsonValue&& item) {
    after_key_ = !is_map_ && !after_key_ && item.kind == JsonValue::Kind::string;
    if (after_key_) pending_key_ = item.text;
    if (!level_) return;
    if (is_map_) {
        budget_.take(sizeof(JsonValue) + key.size());
        out_.keys.push_back(std::move(key));
        out_.items.push_back(std::move(item));
    } else {
        append(std::move(item));
    }
}

void JsonContainerBuilder::add_number(double v) {
    after_key_ = false;
    if (!level_) return;
    if (packing_ == Packing::empty) packing_ = Packing::scalars;
    if (packing_ == Packing::scalars) {
        budget_.take(sizeof(double));
        out_.numbers.push_back(v);
        return;
    }
    JsonValue n;
    n.kind = JsonValue::Kind::number;
    n.number = v;
    append(std::move(n));
}

void JsonContainerBuilder::finish() {
    if (is_map_) return;
    if (packing_ == Packing::scalars) out_.kind = JsonValue::Kind::numbers;
    if (packing_ == Packing::rows) out_.kind = JsonValue::Kind::matrix;
}

// Runs of plain numbers and of equal-length numeric rows (tuples such as [x, y, z]) go into one packed vector
// instead of one node each; anything else turns the array into plain nodes.
void JsonContainerBuilder::append(JsonValue&& item) {
    const bool scalar = item.kind == JsonValue::Kind::number || item.kind == JsonValue::Kind::boolean;
    if (packing_ == Packing::empty) packing_ = scalar ? Packing::scalars : item.is_row() ? Packing::rows : Packing::nodes;
    if (packing_ == Packing::scalars && scalar) {
        budget_.take(sizeof(double));
        out_.numbers.push_back(item.number);
        return;
    }
    if (packing_ == Packing::rows && item.is_row() && (out_.width == 0 || item.size() == out_.width)) {
        out_.width = item.size();
        budget_.take(sizeof(double) * out_.width);
        for (std::uint64_t j = 0; j < out_.width; ++j) out_.numbers.push_back(item.at(j));
        return;
    }
    unpack();
    budget_.take(sizeof(JsonValue));
    out_.items.push_back(std::move(item));
}

// Mixed content after a packed run: the run goes back to nodes (rare; real files are uniform).
void JsonContainerBuilder::unpack() {
    if (packing_ == Packing::nodes) return;
    std::vector<double> packed;
    packed.swap(out_.numbers);
    const std::uint64_t width = packing_ == Packing::rows ? out_.width : 1;
    for (std::size_t i = 0; i + width <= packed.size(); i += static_cast<std::size_t>(width)) {
        budget_.take(sizeof(JsonValue));
        JsonValue v;
        if (packing_ == Packing::rows) {
            v.kind = JsonValue::Kind::numbers;
            v.numbers.assign(packed.begin() + static_cast<std::ptrdiff_t>(i), packed.begin() + static_cast<std::ptrdiff_t>(i + width));
        } else {
            v.kind = JsonValue::Kind::number;
            v.number = packed[i];
        }
        out_.items.push_back(std::move(v));
    }
    out_.width = 0;
    packing_ = Packing::nodes;
}

}  // namespace io_detail
}  // namespace meniscus
