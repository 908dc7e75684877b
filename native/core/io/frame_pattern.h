// Frame sequences of particle (or mesh) files: how a pattern names one file per frame, and which file of a folder
// is which frame. The one rule the command line, the Python API and the Blender add-on share.
//
// A pattern is a prefix, the frame number and a suffix (which includes the extension). Three spellings mean the
// same thing:
//     fluid_0001.bgeo   a concrete file: the last run of digits before the extension is the frame number
//     fluid_####.bgeo   '#' repeated: the number zero-padded to that many digits
//     fluid_{}.bgeo     splashsurf's spelling: the number without padding
// Listing a folder accepts either spelling of a number (fluid_7 and fluid_0007 are both frame 7). When both exist,
// the one spelled with the pattern's own padding wins, else the smaller name: never the folder's listing order.
#pragma once
#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <vector>

namespace meniscus {

struct FramePattern {
    std::string directory;  // UTF-8; empty for the current folder
    std::string prefix, suffix;
    int padding = 0;  // digits of zero-padded frame numbers; 0: unpadded

    std::string file_name(std::int64_t frame) const;
    std::string path(std::int64_t frame) const;
    // '####' spelling ('{}' when unpadded): stored by the add-on and parsed back to the same pattern.
    std::string pattern_string() const;
    // The frame number a file name stands for, when it belongs to this sequence.
    std::optional<std::int64_t> match(const std::string& file_name) const;
};

// True when the name holds a frame-number placeholder ({} or a run of #).
bool has_frame_placeholder(const std::string& path);

// The pattern of a path: a '{}' or '####' pattern, or a concrete file whose last digits are the frame number. For a
// concrete number without a leading zero (fluid_10.vtk), padding is proven only by a sibling with one (fluid_01);
// sibling_names lists the folder's names (nullopt: list the folder). InputError when the name holds no frame number
// or more than one placeholder.
FramePattern parse_frame_pattern(const std::string& path, const std::optional<std::vector<std::string>>& sibling_names = std::nullopt);

struct FrameListing {
    std::map<std::int64_t, std::string> frames;  // frame number -> path, ascending
    std::vector<std::string> duplicates;         // "frame 7: fluid_0007.vtk and fluid_7.vtk; using fluid_7.vtk"
};

// The frames present in the pattern's folder (an empty listing when the folder cannot be read).
FrameListing list_frames(const FramePattern& pattern);

}  // namespace meniscus
