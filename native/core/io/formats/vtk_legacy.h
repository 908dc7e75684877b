// The legacy VTK parser (file format versions 2.0 to 5.1, ASCII and big-endian BINARY), shared by the particle reader
// and the mesh reader (vtk.cpp). Internal to the VTK readers.
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

// Polygons as VTK 5 stores them: polygon i has the vertices connectivity[offsets[i] .. offsets[i + 1]).
struct Polygons {
    std::vector<std::uint64_t> offsets{0};
    std::vector<std::int64_t> connectivity;
    std::size_t count() const { return offsets.size() - 1; }
};

struct Dataset {
    bool unstructured_grid = false;  // DATASET UNSTRUCTURED_GRID (else POLYDATA, or no DATASET line)
    std::vector<float> positions;
    std::vector<PointArray> point_data;
    bool have_polygons = false;
    Polygons polygons;  // only when asked for
};

// What to keep beyond the points and their POINT_DATA.
struct Options {
    bool polygons = false;  // read the POLYGONS section (TRIANGLE_STRIPS are then refused: they would be lost)
};

// Parses the whole source. Cells other than those asked for, CELL_DATA, dataset-level FIELD data, lookup tables and
// METADATA are parsed only to be skipped; counts are checked against the bytes left before anything is allocated.
Dataset read(const Source& source, const Options& options);

}  // namespace vtk_legacy
}  // namespace io_detail
}  // namespace meniscus
