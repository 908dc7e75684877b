// Named per-element float attributes (per particle or per mesh vertex), stored flat: values[i * components + k].
#pragma once
#include <cstddef>
#include <string>
#include <vector>

#include "base/errors.h"

namespace meniscus {

struct Attribute {
    std::string name;
    int components = 1;          // 1 (scalar) or 3 (vector); other counts are allowed and kept as they are
    std::vector<float> values;   // size = count * components
    // Whole numbers from an integer field (ids, labels, flags): carried onto a mesh from the nearest particle, never
    // averaged. float32 holds integers exactly up to 2^24 = 16 777 216.
    bool integral = false;

    std::size_t count() const { return components > 0 ? values.size() / static_cast<std::size_t>(components) : 0; }
};

// A per-element attribute given by the caller, read in place: values[i * components + k].
struct AttributeInput {
    std::string name;
    const float* values = nullptr;
    int components = 1;
    bool integral = false;  // whole numbers (ids, labels): the nearest particle's value, not an average
};

// Throws InputError unless every attribute holds one tuple per element (count of them): "<where>: <element>
// attribute 'name' has N values with C components, expected one tuple per <element> (count)".
inline void require_one_tuple_per_element(const std::vector<Attribute>& attributes, std::size_t count, const std::string& where,
                                          const std::string& element) {
    for (const Attribute& a : attributes)
        if (a.components <= 0 || a.values.size() != count * static_cast<std::size_t>(a.components))
            throw InputError(where + ": " + element + " attribute '" + a.name + "' has " + std::to_string(a.values.size()) +
                             " values with " + std::to_string(a.components) + " components, expected one tuple per " + element +
                             " (" + std::to_string(count) + ")");
}

// Finds an attribute by name; nullptr when absent.
template <class Container>
auto find_attribute(Container& attributes, const std::string& name) -> decltype(&attributes[0]) {
    for (auto& a : attributes)
        if (a.name == name) return &a;
    return nullptr;
}

}  // namespace meniscus
