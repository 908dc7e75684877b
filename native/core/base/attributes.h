// Named per-element float attributes (per particle or per mesh vertex), stored flat: values[i * components + k].
#pragma once
#include <cstddef>
#include <string>
#include <vector>

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

// Finds an attribute by name; nullptr when absent.
template <class Container>
auto find_attribute(Container& attributes, const std::string& name) -> decltype(&attributes[0]) {
    for (auto& a : attributes)
        if (a.name == name) return &a;
    return nullptr;
}

}  // namespace meniscus
