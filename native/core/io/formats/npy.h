// NumPy .npy arrays (format versions 1.0, 2.0 and 3.0) as float columns, for the particle readers (numpy.cpp).
// Internal to the NumPy readers.
#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include "io/io_util.h"

namespace meniscus {
namespace io_detail {

// One named float column of the array: count rows of `components` values.
struct NpyColumn {
    std::string name;
    int components = 1;
    std::vector<float> values;
    bool integral = false;  // from an integer or bool dtype
};
struct NpyArray {
    std::vector<std::uint64_t> shape;
    bool structured = false;
    std::string descr;  // for messages
    std::vector<NpyColumn> columns;
    std::uint64_t rows() const { return shape.empty() ? 1 : shape[0]; }
};

// Parses a whole .npy file: a plain numeric array becomes one column (the product of the dimensions after the first
// as its components; 0 when that exceeds 65536), a structured array one column per numeric field. Object arrays
// (pickles) are refused, never loaded: they could run code.
NpyArray parse_npy(const Source& source);

// "(5, 3)", "(5,)", "()" as Python writes a shape.
std::string shape_text(const std::vector<std::uint64_t>& shape);

}  // namespace io_detail
}  // namespace meniscus
