// Text particle formats: CSV (column groups, special values, errors with line and column) and XYZ (raw float32 or
// text lines).
#include <catch2/catch.hpp>
#include <cmath>
#include <string>
#include <utility>
#include "reader_checks.h"

using namespace meniscus;
using namespace meniscus::test;
namespace fs = std::filesystem;

TEST_CASE("CSV: column groups, special values and errors with line and column", "[formats]") {
    TempDir dir("csv");
    std::string path = dir.file("a.csv");
    write_text(path, "\xef\xbb\xbf# comment\n\nid, x, y, z, v_x, v_y, v_z, \"note\"\n1, 0, 0, 0, 1, 2, 3, 7\n"
                     "2, nan, inf, -inf, 4, 5, 6, 8\n\n");
    ParticleData p = read_particles(path);
    REQUIRE(p.size() == 2);
    CHECK(std::isnan(p.positions[3]));
    CHECK(p.positions[4] == INFINITY);
    REQUIRE(p.attributes.size() == 3);
    CHECK(p.attributes[1].name == "v");
    CHECK(p.attributes[1].components == 3);
    CHECK(p.attributes[1].values == std::vector<float>{1, 2, 3, 4, 5, 6});
    CHECK(p.attributes[2].name == "note");

    write_text(path, "x,y,z\n1,2,3\n4,5\n");
    require_particle_error(path, "line 3 has 2 fields but the header has 3");
    write_text(path, "x,y,z\n1,2,3\n4,five,6\n");
    require_particle_error(path, "line 3, column 'y': bad value 'five'");
    write_text(path, "x,y,z\n1,,3\n");
    require_particle_error(path, "column 'y': empty value");
    write_text(path, "a,b,c\n1,2,3\n");
    require_particle_error(path, "no columns x, y and z");
    write_text(path, "x,y,z\n");
    REQUIRE(read_particles(path).size() == 0);  // a header only: zero particles, like an empty frame
}

TEST_CASE("XYZ: raw size, byte order and text lines", "[formats]") {
    TempDir dir("xyz");
    std::string path = dir.file("a.xyz");
    Bytes raw = read_bytes(kFormats + "/dam26.xyz");
    write_bytes(path, Bytes(raw.begin(), raw.end() - 5));
    require_particle_error(path, "not a multiple of 12");
    Bytes swapped = raw;
    for (std::size_t i = 0; i < swapped.size(); i += 4) {
        std::swap(swapped[i], swapped[i + 3]);
        std::swap(swapped[i + 1], swapped[i + 2]);
    }
    write_bytes(path, swapped);
    require_particle_error(path, "byte-swapped");
    write_text(path, "1 2 3\n4 5 6 7\n");
    require_particle_error(path, "line 2 has 4 values");
    write_text(path, "1,2,3\n# comment\n4;5;6\n");
    REQUIRE(read_particles(path).positions == std::vector<float>{1, 2, 3, 4, 5, 6});
}
