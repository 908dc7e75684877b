// Union-find over the integers [0, n): which elements are connected after a sequence of unions. The root of a set
// is its smallest element, so roots (and anything numbered by them) do not depend on the order of the unions.
#pragma once
#include <cstddef>
#include <cstdint>
#include <numeric>
#include <vector>

namespace meniscus {

class DisjointSets {
public:
    explicit DisjointSets(std::size_t n = 0) { reset(n); }

    // n singletons again; keeps the allocation, for callers that reuse one instance per small problem.
    void reset(std::size_t n) {
        parent_.resize(n);
        std::iota(parent_.begin(), parent_.end(), 0);
    }

    int32_t find(int32_t i) {
        while (parent_[i] != i) i = parent_[i] = parent_[parent_[i]];  // path halving
        return i;
    }

    // Joins the sets of a and b; false when they were one set already.
    bool unite(int32_t a, int32_t b) {
        a = find(a);
        b = find(b);
        if (a == b) return false;
        if (a < b) parent_[b] = a;
        else parent_[a] = b;
        return true;
    }

private:
    std::vector<int32_t> parent_;
};

}  // namespace meniscus
