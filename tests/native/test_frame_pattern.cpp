// Frame patterns (io/frame_pattern.h): the rule the command line, the Python API and the add-on share.
#include <catch2/catch.hpp>
#include <fstream>

#include "base/errors.h"
#include "base/platform.h"
#include "io/frame_pattern.h"
#include "test_files.h"

using namespace meniscus;
using namespace meniscus::test;

namespace {
void touch(const TempDir& dir, const std::string& name) { std::ofstream(path_from_utf8(path_to_utf8(dir.path) + "/" + name)) << "x"; }
}  // namespace

TEST_CASE("the three spellings of a frame pattern", "[frame-pattern]") {
    const std::vector<std::string> none;
    FramePattern p = parse_frame_pattern("d/fluid_{}.vtk", none);
    CHECK((p.directory == "d" && p.prefix == "fluid_" && p.suffix == ".vtk" && p.padding == 0));
    p = parse_frame_pattern("d/fluid_####.bgeo.gz", none);
    CHECK((p.prefix == "fluid_" && p.suffix == ".bgeo.gz" && p.padding == 4));
    p = parse_frame_pattern("d/fluid_0012.bgeo.gz", none);  // the digits of the extension are not the frame number
    CHECK((p.prefix == "fluid_" && p.suffix == ".bgeo.gz" && p.padding == 4));
    p = parse_frame_pattern("ParticleData_Fluid_5.vtk", none);
    CHECK((p.directory.empty() && p.prefix == "ParticleData_Fluid_" && p.padding == 0));
    CHECK(parse_frame_pattern("fluid_10.vtk", std::vector<std::string>{"fluid_09.vtk"}).padding == 2);
    CHECK(parse_frame_pattern("fluid_10.vtk", std::vector<std::string>{"fluid_9.vtk"}).padding == 0);
    CHECK(p.file_name(7) == "ParticleData_Fluid_7.vtk");
    CHECK(parse_frame_pattern("d/x_##.ply", none).file_name(7) == "x_07.ply");
    CHECK(parse_frame_pattern("d/x_##.ply", none).pattern_string() == path_to_utf8(path_from_utf8("d") / "x_##.ply"));
    CHECK_THROWS_WITH(parse_frame_pattern("d/fluid.vtk", none), Catch::Contains("contains no frame number"));
    CHECK_THROWS_WITH(parse_frame_pattern("d/a_{}_{}.vtk", none), Catch::Contains("more than one frame-number placeholder"));
    CHECK_THROWS_AS(parse_frame_pattern("d/a_##_##.vtk", none), InputError);
    CHECK(has_frame_placeholder("a/b_{}.vtk"));
    CHECK(has_frame_placeholder("a/b_###.vtk"));
    CHECK_FALSE(has_frame_placeholder("a{}/b_1.vtk"));  // a placeholder in a folder name is not a frame number
}

TEST_CASE("listing a folder: either spelling of a number, the pattern's own spelling first", "[frame-pattern]") {
    TempDir dir("frames");
    for (const char* name : {"fluid_7.vtk", "fluid_0007.vtk", "fluid_0010.vtk", "fluid_9.vtk", "fluid_x.vtk", "fluid_3.ply",
                             "other_1.vtk", "fluid_-2.vtk"})
        touch(dir, name);
    const std::string folder = path_to_utf8(dir.path);
    const FrameListing padded = list_frames(FramePattern{folder, "fluid_", ".vtk", 4});
    REQUIRE(padded.frames.size() == 3);
    CHECK(path_to_utf8(path_from_utf8(padded.frames.at(7)).filename()) == "fluid_0007.vtk");
    REQUIRE(padded.duplicates.size() == 1);
    CHECK(padded.duplicates[0] == "frame 7: fluid_0007.vtk and fluid_7.vtk; using fluid_0007.vtk");
    const FrameListing unpadded = list_frames(FramePattern{folder, "fluid_", ".vtk", 0});
    CHECK(path_to_utf8(path_from_utf8(unpadded.frames.at(7)).filename()) == "fluid_7.vtk");
    CHECK(unpadded.frames.count(10) == 1);
    CHECK(list_frames(FramePattern{folder + "/missing", "fluid_", ".vtk", 0}).frames.empty());
}

TEST_CASE("frame patterns in folders with non-ASCII names", "[frame-pattern]") {
    TempDir dir("frames_unicode");
    const std::string folder = path_to_utf8(dir.path) + "/\xc3\xa9t\xc3\xa9";  // "été"
    std::filesystem::create_directory(path_from_utf8(folder));
    std::ofstream(path_from_utf8(folder + "/fl\xc3\xbcssig_0003.vtk")) << "x";
    const FramePattern p = parse_frame_pattern(folder + "/fl\xc3\xbcssig_{}.vtk");
    const FrameListing listing = list_frames(p);
    REQUIRE(listing.frames.size() == 1);
    CHECK(listing.frames.at(3) == path_to_utf8(path_from_utf8(folder) / path_from_utf8("fl\xc3\xbcssig_0003.vtk")));
}
