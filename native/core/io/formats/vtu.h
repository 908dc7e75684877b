// The structure of a VTK XML file (.vtu / .vtp) as the reader sees it, shared by the markup pass (vtu.cpp) and the
// array decoding (vtu_arrays.cpp). Internal to the VTK XML reader.
#pragma once
#include <string>
#include <vector>

#include "io/io_util.h"

namespace meniscus {
namespace io_detail {
namespace vtu {

enum class Encoding { ascii, binary, appended };

// One <DataArray> element: its attributes and where its data is.
struct DataArray {
    std::string name;
    std::string type_name;
    ScalarType type = ScalarType::f32;
    bool skip = false;              // String arrays: no float meaning
    std::uint64_t components = 1;
    Encoding encoding = Encoding::ascii;
    std::uint64_t offset = 0;       // appended arrays: from the '_' that starts the appended data
    std::vector<TextRange> text;    // inline arrays: the character data (child elements excluded)
    std::size_t tag_pos = 0;        // for messages
    bool is_points = false;
};

struct Piece {
    std::uint64_t points = 0;
    std::size_t tag_pos = 0;
    bool have_points = false;
    DataArray positions;
    std::vector<DataArray> point_data;
};

// The <AppendedData> element: where its data starts (just after '_') and ends, and every appended DataArray's
// offset (kept or not), sorted, so that each array can be bounded by the next one's start.
struct AppendedData {
    bool present = false, base64 = false;
    std::size_t begin = 0, end = 0;
    std::vector<std::uint64_t> offsets;
};

// What the <VTKFile> element says about every binary array.
struct FileSettings {
    bool big_endian = false;
    std::size_t header_size = 4;  // UInt32 or UInt64 size headers
    bool compressed = false;      // vtkZLibDataCompressor
};

struct File {
    std::string dataset;  // UnstructuredGrid or PolyData
    FileSettings settings;
    std::vector<Piece> pieces;
    AppendedData appended;
};

// "Points DataArray" or "DataArray 'name'", with " of piece N" when the file has several.
std::string array_label(const DataArray& a, std::size_t piece, std::size_t pieces);

// The values of one array of a piece with `tuples` tuples, as floats. Counts are checked against the data before
// anything is allocated; compressed blocks are inflated up to max_inflated_size.
std::vector<float> decode_array(const Cursor& c, const File& file, const DataArray& a, std::uint64_t tuples, const std::string& label);

}  // namespace vtu
}  // namespace io_detail
}  // namespace meniscus
