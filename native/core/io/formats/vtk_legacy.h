// The legacy VTK parser (file format versions 2.0 to 5.1, ASCII and big-endian BINARY) behind the particle reader
// (vtk.cpp). Internal to the VTK reader.
#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include "io/io_util.h"

namespace meniscus {
namespace io_detail {
namespace vtk_legacy {

// One POINT_DATA array, in file order; `section` is its keyword (SCALARS, VECTORS, NORMALS, FIELD, ...).
struct PointArray {
    std::string section;
    Attribute attribute;
};

struct Dataset {
    std::vector<float> positions;
    std::vector<PointArray> point_data;
};

// Parses the whole source. Cells, CELL_DATA, dataset-level FIELD data, lookup tables and
// METADATA are parsed only to be skipped; counts are checked against the bytes left before anything is allocated.
Dataset read(const Source& source);

}  // namespace vtk_legacy
}  // namespace io_detail
}  // namespace meniscus
