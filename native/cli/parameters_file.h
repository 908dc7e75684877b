// The parameters file: one JSON file holding every pipeline parameter of the schema with the frames to work on, so
// that a farm job carries one file instead of forty flags. `meniscus reconstruct --save-parameters FILE` writes it,
// `--parameters FILE` reads it (flags given beside it win), the Python API and the Blender add-on write the same.
//
//   {"meniscus_parameters": 1, "input": "in/fluid_{}.vtk", "output": "out/surface_{}.ply", "start": 1, "end": 240,
//    "interpolate_attributes": ["velocity"], "parameters": {"particle_radius": 0.025, "cube_size": 0.5, ...}}
//
// Every key but "meniscus_parameters" is optional; a parameter left out keeps its default.
#pragma once
#include <optional>
#include <string>
#include <vector>

#include "parameters.h"

namespace meniscus {

inline constexpr int kParametersFileVersion = 1;

struct ParametersFile {
    Parameters parameters;
    std::vector<std::string> given;  // schema names the file sets (the others are at their defaults)
    std::optional<std::string> input, output;
    std::optional<long> start, end;
    std::optional<std::vector<std::string>> attributes;
};

// Frame numbers a run takes and the most frames it spans, checked before it lists (and allocates for) its frames: a
// hand-edited "end": 9223372036854775807 would otherwise ask for a job per frame. Nine digits fit a 32-bit long
// (Windows) and every simulation's numbering; 100 000 frames are over an hour at 24 fps.
inline constexpr long kMaxFrameNumber = 999999999;
inline constexpr long long kMaxFrameCount = 100000;
// What is wrong with frames first..last ("frame numbers go from -999999999 to 999999999, got 1e+19"), or nothing.
std::optional<std::string> frame_range_problem(long long first, long long last);
// "a frame number from -999999999 to 999999999"
std::string allowed_frame_numbers();
// What is wrong with one frame number, or nothing.
std::optional<std::string> frame_number_problem(long long frame);

// The file's text; every schema parameter is written, vectors unset as null.
std::string parameters_file_text(const ParametersFile& file);
// Reads a file's text; `source` names it in messages. InputError naming the key for an unknown key, a value of the
// wrong type, or one out of range: "run.json: parameters.cube_size: must be a number greater than 0, got 0".
ParametersFile parse_parameters_file(const std::string& text, const std::string& source);

ParametersFile read_parameters_file(const std::string& path);
void write_parameters_file(const ParametersFile& file, const std::string& path);

}  // namespace meniscus
