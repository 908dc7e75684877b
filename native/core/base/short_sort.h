// Sorting of the short ranges mesh algorithms handle per vertex (a fan or a ring: about 6 entries on a surface).
#pragma once
#include <algorithm>
#include <functional>
#include <iterator>

namespace meniscus {

// Insertion sort, which beats std::sort on a handful of entries; a long range (a pathological fan) goes to
// std::sort so that nothing turns quadratic.
template <class Iterator, class Less = std::less<>>
void sort_short(Iterator first, Iterator last, Less less = Less()) {
    if (last - first < 2) return;  // also keeps first + 1 off an empty range (a null iterator: undefined)
    if (last - first > 32) {
        std::sort(first, last, less);
        return;
    }
    for (Iterator i = first + 1; i < last; ++i) {
        auto value = std::move(*i);
        Iterator j = i;
        for (; j > first && less(value, *std::prev(j)); --j) *j = std::move(*std::prev(j));
        *j = std::move(value);
    }
}

}  // namespace meniscus
