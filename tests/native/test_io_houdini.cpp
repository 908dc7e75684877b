// Houdini geometry: classic BGEO (attribute types, damaged headers) and JSON geometry (ASCII and binary, every
// value layout, damage and refusals).
#include <catch2/catch.hpp>
#include <cstdio>
#include <random>
#include <string>
#include <vector>
#include "reader_checks.h"

using namespace meniscus;
using namespace meniscus::test;
namespace fs = std::filesystem;

TEST_CASE("BGEO attribute types", "[io]") {
    TempDir dir("bgeo");
    std::string path = dir.file("types.bgeo");
    write_bytes(path, make_bgeo(5, {{"mass", 0, 1}, {"kind", 4, 1}, {"id", 1, 1}, {"v", 5, 3}}));
    ParticleData p = read_particles(path);
    REQUIRE(p.size() == 5);
    REQUIRE(p.positions[3 * 4 + 2] == 12.0f);
    REQUIRE(p.attributes.size() == 3);  // the index (string table) attribute is skipped
    CHECK(p.attributes[0].name == "mass");
    CHECK(p.attributes[0].values == std::vector<float>{0, 10, 20, 30, 40});
    CHECK(p.attributes[1].name == "id");
    CHECK(p.attributes[1].values == std::vector<float>{0, 10, 20, 30, 40});
    CHECK(p.attributes[2].name == "v");
    CHECK(p.attributes[2].components == 3);
    CHECK(p.attributes[2].values[3 * 4 + 2] == 42.0f);

    std::string string_attr = dir.file("string.bgeo");
    write_bytes(string_attr, make_bgeo(2, {{"name", 2, 1}}));
    require_particle_error(string_attr, "unsupported BGEO variant");
    std::string unknown_attr = dir.file("unknown.bgeo");
    write_bytes(unknown_attr, make_bgeo(2, {{"odd", 9, 1}}));
    require_particle_error(unknown_attr, "unsupported BGEO variant");
    std::string v4 = dir.file("v4.bgeo");
    write_bytes(v4, gzip(make_bgeo(2, {}, 4)));
    require_particle_error(v4, "unsupported BGEO variant: version 4");
    std::string json = dir.file("json.bgeo");
    write_text(json, std::string("\x7fNSJ") + "[\"fileversion\"]");
    require_particle_error(json, "unsupported BGEO variant");
}

TEST_CASE("damaged counts and types in BGEO headers give FormatError", "[io]") {
    TempDir dir("bgeocounts");
    const Bytes raw = gunzip_file(kShared + "/splashsurf/dam_break_frame_9_6859_particles.bgeo");
    std::string path = dir.file("damaged.bgeo");
    auto with_word = [&](std::size_t offset, std::uint32_t value) {
        Bytes copy = raw;
        for (int k = 0; k < 4; ++k) copy.at(offset + k) = static_cast<unsigned char>(value >> (24 - 8 * k));
        return copy;
    };
    // Layout: magic 0..4, version 5..8, counts 9..40 (points at 9, point attributes at 25).
    struct Case {
        Bytes bytes;
        const char* expect;
    };
    std::vector<Case> cases = {
        {with_word(9, 0x7fffffff), "needs"},
        {with_word(9, 0x80000000), "negative point count"},
        {with_word(9, 6860), "truncated at byte"},
        {with_word(25, 0x7fffffff), "point attribute count"},
        {with_word(25, 0xffffffff), "negative point attribute count"},
        {with_word(5, 6), "unsupported BGEO variant: version 6"},
        // The first attribute ("id") starts at 41: name length (2), name (2), size (2), then its type at 47.
        {with_word(47, 2), "unsupported BGEO variant"},
        {with_word(47, 77), "unsupported BGEO variant"},
    };
    Bytes bad_magic = raw;
    bad_magic[4] = 'X';
    cases.push_back({bad_magic, "unsupported BGEO variant"});
    Bytes big_name = raw;
    big_name[41] = 0xff;  // name length 0xff02
    cases.push_back({big_name, ""});
    Bytes big_size = raw;
    big_size[45] = 0xff;  // attribute size 0xff01 words
    cases.push_back({big_size, ""});
    for (auto& c : cases) {
        write_bytes(path, gzip(c.bytes));
        require_particle_error(path, c.expect);
    }
    // Random damage to the header, written uncompressed (plain BGEO reads the same) to keep the test quick.
    std::mt19937 rng(5);
    for (int trial = 0; trial < 300; ++trial) {
        Bytes copy = raw;
        copy[rng() % 120] = static_cast<unsigned char>(rng());
        write_bytes(path, copy);
        require_clean_outcome(path);
    }
}

TEST_CASE("Houdini JSON geometry: ASCII and binary, every value layout", "[formats]") {
    const std::string v = kFormats + "/variants/";
    for (const char* name : {"houdini_tuples.geo", "houdini_arrays.geo", "houdini_paged_le.bgeo"}) {
        INFO(name);
        ParticleData p = read_particles(v + name);
        require_same(p, 5, true, true, "v");  // the string attribute "name" is skipped
    }
    // Big-endian, with velocity's second page (particles 2 and 3) stored once as a constant page.
    ParticleData p = read_particles(v + "houdini_constant_be.bgeo");
    REQUIRE(p.size() == 5);
    REQUIRE(std::equal(p.positions.begin(), p.positions.end(), reference().positions.begin()));
    const Attribute* vel = find_attribute(p.attributes, std::string("v"));
    REQUIRE(vel);
    std::vector<float> expected(reference().attributes[1].values.begin(), reference().attributes[1].values.begin() + 15);
    for (int k = 0; k < 3; ++k) expected[9 + k] = expected[6 + k];
    REQUIRE(vel->values == expected);
}

TEST_CASE("Houdini JSON geometry: a whole frame as ASCII tuples and arrays", "[formats]") {
    // Large tuple lists are packed as they are parsed (no node per point); component arrays longer than a tuple
    // stay arrays. Both must give the frame back exactly (9 significant digits round-trip float32).
    const ParticleData& ref = reference();
    const std::size_t n = ref.size();
    char buf[32];
    auto num = [&](float v) {
        std::snprintf(buf, sizeof buf, "%.9g", v);
        return std::string(buf);
    };
    for (bool tuples : {true, false}) {
        std::string doc = "[\"fileversion\",\"19.5.303\",\"pointcount\"," + std::to_string(n) +
                          ",\"attributes\",[\"pointattributes\",[";
        auto attribute = [&](const std::string& name, const std::vector<float>& values, int k, bool last) {
            doc += "[[\"scope\",\"public\",\"type\",\"numeric\",\"name\",\"" + name + "\"],[\"size\"," + std::to_string(k) +
                   ",\"storage\",\"fpreal32\",\"values\",[\"size\"," + std::to_string(k) + ",\"storage\",\"fpreal32\",";
            if (tuples) {
                doc += "\"tuples\",[";
                for (std::size_t i = 0; i < n; ++i) {
                    doc += i ? ",[" : "[";
                    for (int j = 0; j < k; ++j) doc += (j ? "," : "") + num(values[i * k + j]);
                    doc += "]";
                }
            } else {
                doc += "\"arrays\",[";
                for (int j = 0; j < k; ++j) {
                    doc += j ? ",[" : "[";
                    for (std::size_t i = 0; i < n; ++i) doc += (i ? "," : "") + num(values[i * k + j]);
                    doc += "]";
                }
            }
            doc += "]]]]";
            doc += last ? "" : ",";
        };
        attribute("P", ref.positions, 3, false);
        attribute("v", ref.attributes[1].values, 3, true);
        doc += "]]]";
        TempDir dir("houdini_frame");
        std::string path = dir.file("frame.geo");
        write_text(path, doc);
        INFO((tuples ? "tuples" : "arrays"));
        require_same(read_particles(path), n, false, true, "v");
    }
}

TEST_CASE("Houdini JSON geometry: damage and refusals", "[formats]") {
    TempDir dir("houdini_bad");
    std::string path = dir.file("g.geo");
    std::string text = as_text(read_bytes(kFormats + "/variants/houdini_tuples.geo"));
    std::string bad = text;
    bad.replace(bad.find("\"pointcount\",5"), 14, "\"pointcount\",6");
    write_text(path, bad);
    require_particle_error(path, "has 5 numeric tuples for 6 points");
    bad = text;
    bad.replace(bad.find("\"pointcount\",5"), 14, "\"pointcount\",-1");
    write_text(path, bad);
    require_particle_error(path, "without a valid \"pointcount\"");
    bad = text;
    bad.replace(bad.find("\"name\",\"P\""), 10, "\"name\",\"Q\"");
    write_text(path, bad);
    require_particle_error(path, "has no numeric point attribute P");
    write_text(path, std::string(200, '[') + "\"pointcount\"");
    require_particle_error(path, "nested more than 64 levels");

    path = dir.file("g.bgeo");
    Bytes binary = read_bytes(kFormats + "/variants/houdini_paged_le.bgeo");
    Bytes cut(binary.begin(), binary.end() - 40);
    write_bytes(path, cut);
    require_particle_error(path, "truncated");
    Bytes magic = binary;
    magic[4] = 'x';
    write_bytes(path, magic);
    require_particle_error(path, "unsupported BGEO variant: a binary JSON header");

    // Blosc-compressed .sc: by extension, and by its "scf1" header under any name.
    std::string sc = dir.file("fluid.0001.bgeo.sc");
    write_bytes(sc, Bytes{0x62, 0x6c, 0x6f, 0x73, 0x63, 1, 2, 3});
    require_particle_error(sc, "Blosc");
    std::string scf = dir.file("fluid.0001.bgeo");
    write_bytes(scf, as_bytes("scf1" + std::string(40, '\0')));
    require_particle_error(scf, "Blosc");
    std::string geo = dir.file("fluid.geo");
    write_text(geo, "PGEOMETRY V5\nNPoints 1 NPrims 0\n");
    require_particle_error(geo, "unsupported BGEO variant: ASCII .geo");
}
