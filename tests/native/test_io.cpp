// Tests of the particle readers and mesh writers / readers (native/core/io*.cpp).
#include <zlib.h>

#include <catch2/catch.hpp>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <random>
#include <set>
#include <string>
#include <vector>

#include "base/errors.h"
#include "base/platform.h"
#include "io/io.h"
#include "test_files.h"

using namespace meniscus;
using namespace meniscus::test;
namespace fs = std::filesystem;

namespace {

const std::string kShared = MENISCUS_SHARED_DATA;
const std::string kTestData = MENISCUS_TEST_DATA;

Bytes gunzip_file(const std::string& path) {
    gzFile f = gzopen(path.c_str(), "rb");
    REQUIRE(f != nullptr);
    Bytes out;
    unsigned char buffer[1 << 16];
    int n;
    while ((n = gzread(f, buffer, sizeof buffer)) > 0) out.insert(out.end(), buffer, buffer + n);
    gzclose(f);
    return out;
}

// Runs f; returns the FormatError message, or "" when f succeeds. Any other exception fails the test.
template <class F>
std::string format_error_of(F&& f) {
    try {
        f();
    } catch (const FormatError& e) {
        return e.what();
    }
    return "";
}

bool starts_with(const std::string& s, const std::string& prefix) { return s.rfind(prefix, 0) == 0; }

// read_particles(path) must fail with a FormatError that starts with the path (and contains `expect` if given).
std::string require_particle_error(const std::string& path, const std::string& expect = "") {
    std::string message = format_error_of([&] { read_particles(path); });
    INFO("path: " << path << "\nmessage: " << message);
    REQUIRE(!message.empty());
    REQUIRE(starts_with(message, path));
    if (!expect.empty()) REQUIRE_THAT(message, Catch::Contains(expect));
    return message;
}

std::string require_mesh_error(const std::string& path, const std::string& expect = "") {
    std::string message = format_error_of([&] { read_mesh(path); });
    INFO("path: " << path << "\nmessage: " << message);
    REQUIRE(!message.empty());
    REQUIRE(starts_with(message, path));
    if (!expect.empty()) REQUIRE_THAT(message, Catch::Contains(expect));
    return message;
}

// Either a clean read or a FormatError naming the path: what every damaged file must give.
void require_clean_outcome(const std::string& path) {
    std::string message = format_error_of([&] { read_particles(path); });
    INFO("path: " << path << "\nmessage: " << message);
    if (!message.empty()) REQUIRE(starts_with(message, path));
}

struct AttrSpec {
    std::string name;
    int components;
};

struct FileSpec {
    std::string path;  // relative to the shared data directory
    std::size_t count;
    std::vector<AttrSpec> attributes;
};

const std::vector<FileSpec>& shared_files() {
    static const std::vector<FileSpec> files = {
        {"splashsurf/bunny_frame_14_7705_particles.vtk", 7706, {{"id", 1}, {"velocity", 3}}},
        {"splashsurf/double_dam_break_frame_01_4732_particles.vtk", 4732, {{"id", 1}, {"velocity", 3}}},
        {"splashsurf/double_dam_break_frame_26_4732_particles.vtk", 4732, {{"id", 1}, {"velocity", 3}}},
        {"splashsurf/hilbert2_7954_particles.vtk", 7954, {{"id", 1}}},
        {"splashsurf/ParticleData_Fluid_5.vtk", 4732, {{"id", 1}, {"velocity", 3}}},
        {"splashsurf/dam_break_frame_9_6859_particles.bgeo", 6859, {{"id", 1}, {"density", 1}, {"velocity", 3}}},
        {"splashsurf/hilbert_46843_particles.bgeo", 46843, {}},
        {"splashsurf/pentagonal_hexecontahedron_32286_particles.bgeo", 32286, {}},
        {"splashsurf/ParticleData_Fluid_50.bgeo", 4732, {{"id", 1}, {"velocity", 3}}},
        {"sequence/double_dam_break_0000.vtk", 12096, {{"id", 1}, {"velocity", 3}}},
    };
    return files;
}

void check_particles(const ParticleData& p, const FileSpec& spec) {
    INFO(spec.path);
    REQUIRE(p.positions.size() == 3 * spec.count);
    REQUIRE(p.size() == spec.count);
    REQUIRE(p.attributes.size() == spec.attributes.size());
    for (std::size_t i = 0; i < spec.attributes.size(); ++i) {
        const Attribute& a = p.attributes[i];
        CHECK(a.name == spec.attributes[i].name);
        CHECK(a.components == spec.attributes[i].components);
        CHECK(a.count() == spec.count);
        // One assertion per array, not per value: the value loops run millions of times.
        std::size_t bad = 0;
        for (float v : a.values) bad += !std::isfinite(v) || (a.name == "id" && (v < 0 || v != std::floor(v)));
        REQUIRE(bad == 0);
    }
    // The scenes are a few metres across at most.
    std::size_t bad = 0;
    for (float x : p.positions) bad += !(std::isfinite(x) && std::fabs(x) < 50.0f);
    REQUIRE(bad == 0);
}

// Offsets of the keyword lines ("\nPOINTS ...", "\nCELLS ...") in a binary legacy VTK file.
std::vector<std::size_t> vtk_keyword_offsets(const Bytes& bytes) {
    static const char* keywords[] = {"POINTS ", "CELLS ", "CELL_TYPES ", "POINT_DATA ", "SCALARS ", "LOOKUP_TABLE ", "FIELD "};
    std::vector<std::size_t> out;
    for (std::size_t i = 1; i < bytes.size(); ++i) {
        if (bytes[i - 1] != '\n') continue;
        for (const char* k : keywords)
            if (bytes.size() - i > std::strlen(k) && std::memcmp(&bytes[i], k, std::strlen(k)) == 0) out.push_back(i);
    }
    return out;
}

// Replaces the first occurrence of `from` by `to` (same file otherwise).
Bytes replace_text(const Bytes& bytes, const std::string& from, const std::string& to) {
    std::string s(bytes.begin(), bytes.end());
    auto pos = s.find(from);
    REQUIRE(pos != std::string::npos);
    s.replace(pos, from.size(), to);
    return Bytes(s.begin(), s.end());
}

// ---- builders for synthetic binary files ----

struct BigEndianWriter {
    Bytes bytes;
    void text(const std::string& s) { bytes.insert(bytes.end(), s.begin(), s.end()); }
    void u8(unsigned v) { bytes.push_back(static_cast<unsigned char>(v)); }
    void u16(unsigned v) {
        u8(v >> 8);
        u8(v);
    }
    void u32(std::uint32_t v) {
        u16(v >> 16);
        u16(v & 0xffff);
    }
    void u64(std::uint64_t v) {
        u32(static_cast<std::uint32_t>(v >> 32));
        u32(static_cast<std::uint32_t>(v));
    }
    void f32(float f) {
        std::uint32_t u;
        std::memcpy(&u, &f, 4);
        u32(u);
    }
    void f64(double d) {
        std::uint64_t u;
        std::memcpy(&u, &d, 8);
        u64(u);
    }
};

struct BgeoAttr {
    std::string name;
    int type;  // 0 float, 1 int, 4 index, 5 vector
    int size;
};

// A classic BGEO with the given attributes; point i has position (i, 2i, 3i) and attribute word k = i * 10 + k.
Bytes make_bgeo(std::int32_t points, const std::vector<BgeoAttr>& attrs, int version = 5) {
    BigEndianWriter w;
    w.text("BgeoV");
    w.u32(static_cast<std::uint32_t>(version));
    for (std::int32_t c : {points, 0, 0, 0, static_cast<std::int32_t>(attrs.size()), 0, 0, 0}) w.u32(static_cast<std::uint32_t>(c));
    for (const auto& a : attrs) {
        w.u16(static_cast<unsigned>(a.name.size()));
        w.text(a.name);
        w.u16(static_cast<unsigned>(a.size));
        w.u32(static_cast<std::uint32_t>(a.type));
        if (a.type == 4) {
            w.u32(2);
            for (const char* s : {"water", "foam"}) {
                w.u16(static_cast<unsigned>(std::strlen(s)));
                w.text(s);
            }
        } else {
            for (int k = 0; k < a.size; ++k) w.u32(0);
        }
    }
    for (std::int32_t i = 0; i < points; ++i) {
        w.f32(float(i));
        w.f32(float(2 * i));
        w.f32(float(3 * i));
        w.f32(1.0f);
        for (const auto& a : attrs)
            for (int k = 0; k < a.size; ++k) {
                if (a.type == 0 || a.type == 5)
                    w.f32(float(i * 10 + k));
                else
                    w.u32(static_cast<std::uint32_t>(a.type == 4 ? i % 2 : i * 10 + k));
            }
    }
    w.u8(0);
    w.u8(0xff);
    return w.bytes;
}

TriMesh make_test_mesh() {
    // An octahedron: 6 vertices, 8 triangles, unit normals, attributes of 1, 3 and 2 components.
    TriMesh m;
    m.vertices = {1, 0, 0, -1, 0, 0, 0, 1, 0, 0, -1, 0, 0, 0, 1, 0, 0, -1};
    m.triangles = {0, 2, 4, 2, 1, 4, 1, 3, 4, 3, 0, 4, 2, 0, 5, 1, 2, 5, 3, 1, 5, 0, 3, 5};
    m.normals = m.vertices;
    for (float& x : m.vertices) x = x * 0.3f + 0.1f;  // values that are not short decimals
    Attribute density{"density", 1, {}}, velocity{"velocity", 3, {}}, uv{"uv", 2, {}};
    for (int v = 0; v < 6; ++v) {
        density.values.push_back(1000.0f + v / 7.0f);
        for (int k = 0; k < 3; ++k) velocity.values.push_back(std::sin(float(v * 3 + k)));
        for (int k = 0; k < 2; ++k) uv.values.push_back(v * 0.1f + k);
    }
    m.attributes = {density, velocity, uv};
    return m;
}

void require_same_mesh(const TriMesh& a, const TriMesh& b, bool with_attributes) {
    REQUIRE(a.vertices == b.vertices);
    REQUIRE(a.triangles == b.triangles);
    REQUIRE(a.normals == b.normals);
    if (!with_attributes) return;
    REQUIRE(a.attributes.size() == b.attributes.size());
    for (std::size_t i = 0; i < a.attributes.size(); ++i) {
        CHECK(a.attributes[i].name == b.attributes[i].name);
        CHECK(a.attributes[i].components == b.attributes[i].components);
        CHECK(a.attributes[i].values == b.attributes[i].values);
    }
}

}  // namespace

// ---------------------------------------------------------------------------------------------------------------
// Shared data files

TEST_CASE("every shared particle file reads with its count and attributes", "[io]") {
    for (const auto& spec : shared_files()) {
        ParticleData p = read_particles(kShared + "/" + spec.path);
        check_particles(p, spec);
    }
}

TEST_CASE("file names with non-ASCII characters read and write on every platform", "[io]") {
    // Windows opens files by UTF-16 names: a UTF-8 path must never reach a narrow-character API there.
    TempDir dir("unicode");
    const std::string folder = path_to_utf8(dir.path) + "/\xc3\xa9t\xc3\xa9 \xe7\xb2\x92\xe5\xad\x90";  // "été 粒子"
    fs::create_directory(path_from_utf8(folder));
    const std::string source = kShared + "/splashsurf/bunny_frame_14_7705_particles.vtk";
    const std::string particles = folder + "/fluid_\xc3\xa9t\xc3\xa9_0001.vtk";
    fs::copy_file(path_from_utf8(source), path_from_utf8(particles));
    const ParticleData original = read_particles(source), copy = read_particles(particles);
    REQUIRE(copy.positions == original.positions);

    TriMesh mesh;
    mesh.vertices = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1};
    mesh.triangles = {0, 2, 1, 0, 1, 3, 0, 3, 2, 1, 2, 3};
    for (const char* extension : {".ply", ".obj", ".vtk"}) {
        const std::string path = folder + "/surface_\xe7\xb2\x92\xe5\xad\x90" + extension;
        write_mesh(mesh, path);
        REQUIRE(fs::is_regular_file(path_from_utf8(path)));
        if (std::string(extension) != ".vtk") REQUIRE(read_mesh(path).vertices == mesh.vertices);
    }
    // Errors name the file as the user spelled it.
    const std::string missing = folder + "/missing_\xc3\xa9.vtk";
    REQUIRE_THROWS_WITH(read_particles(missing), Catch::StartsWith(missing));
}

TEST_CASE("the sequence frames all read, with stable ids", "[io]") {
    std::set<float> first_ids;
    int frames = 0;
    for (int f = 0; f <= 60; ++f) {
        char name[64];
        std::snprintf(name, sizeof name, "sequence/double_dam_break_%04d.vtk", f);
        ParticleData p = read_particles(kShared + "/" + name);
        check_particles(p, {name, 12096, {{"id", 1}, {"velocity", 3}}});
        std::set<float> ids(p.attributes[0].values.begin(), p.attributes[0].values.end());
        REQUIRE(ids.size() == 12096);  // unique
        if (f == 0)
            first_ids = ids;
        else
            REQUIRE(ids == first_ids);
        // The domain is the box [0, 3] x [0, 1.2] x [0, 2]; allow for particles pushed slightly through a wall.
        std::size_t outside = 0;
        for (std::size_t i = 0; i < p.size(); ++i)
            outside += !(p.positions[3 * i] > -0.2f && p.positions[3 * i] < 3.2f && p.positions[3 * i + 1] > -0.2f &&
                         p.positions[3 * i + 1] < 1.4f && p.positions[3 * i + 2] > -0.2f && p.positions[3 * i + 2] < 2.2f);
        REQUIRE(outside == 0);
        ++frames;
    }
    REQUIRE(frames == 61);
}

TEST_CASE("VTK positions match an independent decoding of the binary block", "[io]") {
    const std::string path = kShared + "/splashsurf/bunny_frame_14_7705_particles.vtk";
    Bytes bytes = read_bytes(path);
    const std::string header = "POINTS 7706 float\n";
    std::string s(bytes.begin(), bytes.end());
    std::size_t start = s.find(header);
    REQUIRE(start != std::string::npos);
    start += header.size();
    ParticleData p = read_particles(path);
    REQUIRE(p.size() == 7706);
    std::vector<float> decoded(3 * 7706);
    for (std::size_t i = 0; i < decoded.size(); ++i) {
        const unsigned char* b = &bytes[start + 4 * i];
        std::uint32_t u = (std::uint32_t(b[0]) << 24) | (std::uint32_t(b[1]) << 16) | (std::uint32_t(b[2]) << 8) | b[3];
        std::memcpy(&decoded[i], &u, 4);
    }
    REQUIRE(p.positions == decoded);
}

TEST_CASE("a binary VTK frame and its ASCII conversion read the same", "[io]") {
    TempDir dir("ascii");
    for (const char* name : {"splashsurf/bunny_frame_14_7705_particles.vtk", "sequence/double_dam_break_0030.vtk"}) {
        ParticleData binary = read_particles(kShared + "/" + name);
        const std::size_t n = binary.size();
        // Same structure as the original: POINTS, one VERTEX cell per point, then the point data.
        std::string text = "# vtk DataFile Version 4.1\nconverted to ASCII by test_io\nASCII\nDATASET UNSTRUCTURED_GRID\n";
        char buf[64];
        auto put = [&](float v) {
            std::snprintf(buf, sizeof buf, "%.9g ", v);
            text += buf;
        };
        text += "POINTS " + std::to_string(n) + " float\n";
        for (std::size_t i = 0; i < n; ++i) {
            for (int k = 0; k < 3; ++k) put(binary.positions[3 * i + k]);
            text += "\n";
        }
        text += "CELLS " + std::to_string(n) + " " + std::to_string(2 * n) + "\n";
        for (std::size_t i = 0; i < n; ++i) text += "1 " + std::to_string(i) + "\n";
        text += "CELL_TYPES " + std::to_string(n) + "\n";
        for (std::size_t i = 0; i < n; ++i) text += "1\n";
        text += "POINT_DATA " + std::to_string(n) + "\nSCALARS id unsigned_int 1\nLOOKUP_TABLE default\n";
        for (float v : binary.attributes[0].values) text += std::to_string(static_cast<long long>(v)) + "\n";
        text += "FIELD FieldData 1\nvelocity 3 " + std::to_string(n) + " float\n";
        for (float v : binary.attributes[1].values) put(v);
        text += "\n";
        std::string path = dir.file("ascii.vtk");
        write_text(path, text);

        ParticleData ascii = read_particles(path);
        REQUIRE(ascii.positions == binary.positions);
        REQUIRE(ascii.attributes.size() == 2);
        CHECK(ascii.attributes[0].name == "id");
        CHECK(ascii.attributes[1].name == "velocity");
        CHECK(ascii.attributes[1].components == 3);
        REQUIRE(ascii.attributes[0].values == binary.attributes[0].values);
        REQUIRE(ascii.attributes[1].values == binary.attributes[1].values);
    }
}

TEST_CASE("gzip-compressed VTK and plain BGEO are detected by content", "[io]") {
    TempDir dir("gz");
    const std::string vtk = kShared + "/splashsurf/hilbert2_7954_particles.vtk";
    ParticleData reference = read_particles(vtk);
    std::string gz = dir.file("frame.vtk.gz");
    write_bytes(gz, gzip(read_bytes(vtk)));
    ParticleData from_gz = read_particles(gz);
    REQUIRE(from_gz.positions == reference.positions);
    REQUIRE(from_gz.attributes.size() == 1);

    // A decompressed BGEO under a misleading extension is still a BGEO.
    const std::string bgeo = kShared + "/splashsurf/ParticleData_Fluid_50.bgeo";
    std::string plain = dir.file("frame.dat");
    write_bytes(plain, gunzip_file(bgeo));
    ParticleData a = read_particles(bgeo), b = read_particles(plain);
    REQUIRE(a.positions == b.positions);
    REQUIRE(b.attributes.size() == 2);
    REQUIRE(a.attributes[1].values == b.attributes[1].values);

    // Two concatenated gzip members decompress as one stream (like gzip -d does).
    Bytes raw = gunzip_file(bgeo);
    Bytes first(raw.begin(), raw.begin() + 1000), second(raw.begin() + 1000, raw.end());
    Bytes joined = gzip(first), tail = gzip(second);
    joined.insert(joined.end(), tail.begin(), tail.end());
    std::string multi = dir.file("multi.bgeo");
    write_bytes(multi, joined);
    REQUIRE(read_particles(multi).positions == a.positions);
}

// ---------------------------------------------------------------------------------------------------------------
// Synthetic files: every section and type

TEST_CASE("ASCII POLYDATA with every attribute section", "[io]") {
    ParticleData p = read_particles(kTestData + "/io/ascii_polydata.vtk");
    REQUIRE(p.size() == 4);
    REQUIRE(p.positions == std::vector<float>{0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1.5f});
    REQUIRE(p.attributes.size() == 5);
    CHECK(p.attributes[0].name == "density");
    CHECK(p.attributes[0].values == std::vector<float>{1000.5f, 999, 1001, -2.5e-3f});
    CHECK(p.attributes[1].name == "velocity");
    CHECK(p.attributes[1].components == 3);
    CHECK(p.attributes[1].values[11] == -3.0f);
    CHECK(p.attributes[2].name == "pressure kpa");  // %20 decoded
    CHECK(p.attributes[3].name == "id");
    CHECK(p.attributes[3].values == std::vector<float>{10, 11, 12, 13});
    CHECK(p.attributes[4].name == "flag");
    CHECK(p.attributes[4].components == 2);
    CHECK(p.attributes[4].values.back() == 255.0f);
}

TEST_CASE("VTK 5.1 cells and METADATA are skipped", "[io]") {
    ParticleData p = read_particles(kTestData + "/io/vtk51_ascii.vtk");
    REQUIRE(p.size() == 3);
    REQUIRE(p.positions[8] == 2.0f);
    REQUIRE(p.attributes.size() == 2);
    CHECK(p.attributes[0].name == "id");
    CHECK(p.attributes[0].values == std::vector<float>{5, 6, 7});
    CHECK(p.attributes[1].name == "velocity");
    CHECK(p.attributes[1].values[8] == -0.75f);
}

TEST_CASE("binary VTK with double points, many types, 5.x cells and cell data", "[io]") {
    TempDir dir("binvtk");
    for (int version : {4, 5}) {
        BigEndianWriter w;
        w.text(version == 5 ? "# vtk DataFile Version 5.1\n" : "# vtk DataFile Version 4.2\n");
        w.text("\nBINARY\nDATASET POLYDATA\nPOINTS 3 double\n");  // empty title line
        for (int i = 0; i < 9; ++i) w.f64(i * 0.5);
        if (version == 5) {
            w.text("\nVERTICES 4 3\nOFFSETS vtktypeint64\n");
            for (int i = 0; i < 4; ++i) w.u64(static_cast<std::uint64_t>(i));
            w.text("\nCONNECTIVITY vtktypeint64\n");
            for (int i = 0; i < 3; ++i) w.u64(static_cast<std::uint64_t>(i));
        } else {
            w.text("\nVERTICES 3 6\n");
            for (int i = 0; i < 3; ++i) {
                w.u32(1);
                w.u32(static_cast<std::uint32_t>(i));
            }
        }
        w.text("\nCELL_DATA 3\nSCALARS skipped double\nLOOKUP_TABLE default\n");
        for (int i = 0; i < 3; ++i) w.f64(1e300);
        // The first data byte is 0x0a ('\n'): it must not be taken for the end of the header line.
        w.text("\nPOINT_DATA 3\nSCALARS code int\nLOOKUP_TABLE default\n");
        for (std::uint32_t v : {0x0a0b0c0du, 0x20u, 0xffffffffu}) w.u32(v);
        w.text("\nSCALARS small short 2\nLOOKUP_TABLE default\n");
        for (int v : {-1, 2, -3, 4, -5, 6}) w.u16(static_cast<std::uint16_t>(v));
        w.text("\nVECTORS vel double\n");
        for (int i = 0; i < 9; ++i) w.f64(-i * 0.25);
        w.text("\nNORMALS n float\n");
        for (int i = 0; i < 9; ++i) w.f32(1.0f);
        w.text("\nFIELD FieldData 4\nbig 1 3 vtktypeint64\n");
        for (std::int64_t v : {std::int64_t(-7), std::int64_t(1) << 40, std::int64_t(0)}) w.u64(static_cast<std::uint64_t>(v));
        if (version == 5) w.text("\nMETADATA\nINFORMATION 1\nNAME L2_NORM_RANGE LOCATION vtkDataArray\nDATA 2 0 1\n");
        w.text("\nbytes 1 3 unsigned_char\n");
        for (unsigned v : {0u, 128u, 255u}) w.u8(v);
        w.text("\nNULL_ARRAY\nushort 1 3 unsigned_short\n");
        for (unsigned v : {0u, 1u, 65535u}) w.u16(v);
        w.text("\n");
        std::string path = dir.file("types" + std::to_string(version) + ".vtk");
        write_bytes(path, w.bytes);

        ParticleData p = read_particles(path);
        REQUIRE(p.size() == 3);
        REQUIRE(p.positions[8] == 4.0f);
        REQUIRE(p.attributes.size() == 7);
        CHECK(p.attributes[0].name == "code");
        CHECK(p.attributes[0].values == std::vector<float>{float(0x0a0b0c0d), 32.0f, -1.0f});
        CHECK(p.attributes[1].components == 2);
        CHECK(p.attributes[1].values == std::vector<float>{-1, 2, -3, 4, -5, 6});
        CHECK(p.attributes[2].values[8] == -2.0f);
        CHECK(p.attributes[3].name == "n");
        CHECK(p.attributes[4].values == std::vector<float>{-7.0f, float(std::int64_t(1) << 40), 0.0f});
        CHECK(p.attributes[5].values == std::vector<float>{0, 128, 255});
        CHECK(p.attributes[6].name == "ushort");
        CHECK(p.attributes[6].values == std::vector<float>{0, 1, 65535});
    }
}

TEST_CASE("zero particles is valid", "[io]") {
    TempDir dir("zero");
    std::string vtk = dir.file("empty.vtk");
    write_text(vtk, "# vtk DataFile Version 4.1\nnothing\nBINARY\nDATASET UNSTRUCTURED_GRID\nPOINTS 0 float\n\n"
                    "CELLS 0 0\n\nCELL_TYPES 0\n\nPOINT_DATA 0\nSCALARS id int 1\nLOOKUP_TABLE default\n\n");
    ParticleData p = read_particles(vtk);
    REQUIRE(p.size() == 0);
    REQUIRE(p.attributes.size() == 1);
    REQUIRE(p.attributes[0].values.empty());

    std::string bgeo = dir.file("empty.bgeo");
    write_bytes(bgeo, gzip(make_bgeo(0, {{"v", 5, 3}})));
    ParticleData q = read_particles(bgeo);
    REQUIRE(q.size() == 0);
    REQUIRE(q.attributes.size() == 1);
}

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

// ---------------------------------------------------------------------------------------------------------------
// Damaged files

TEST_CASE("empty, garbage, directory and missing paths give FormatError", "[io]") {
    TempDir dir("bad");
    std::string empty = dir.file("empty.vtk");
    write_text(empty, "");
    REQUIRE_THROWS_AS(read_particles(empty), FormatError);
    require_particle_error(empty, "empty file");

    REQUIRE_THROWS_AS(read_particles(dir.path.string()), FormatError);
    require_particle_error(dir.path.string(), "directory");
    std::string missing = dir.file("missing.vtk");
    REQUIRE_THROWS_AS(read_particles(missing), FormatError);
    require_particle_error(missing, "cannot open");
    REQUIRE_THROWS_AS(read_particles(""), FormatError);

    std::mt19937 rng(7);
    for (const char* ext : {".vtk", ".bgeo", ".dat", ".bgeo.gz"}) {
        for (int trial = 0; trial < 20; ++trial) {
            Bytes garbage(1 + rng() % 5000);
            for (auto& b : garbage) b = static_cast<unsigned char>(rng());
            std::string path = dir.file(std::string("garbage") + ext);
            write_bytes(path, trial % 2 ? gzip(garbage) : garbage);
            REQUIRE_THROWS_AS(read_particles(path), FormatError);
            require_particle_error(path);
        }
    }
    // Garbage after a valid magic.
    for (const std::string magic : {"# vtk DataFile Version 4.1\n", "BgeoV", "# vtk DataFile Version 4.1\nt\nBINARY\n"}) {
        for (int trial = 0; trial < 20; ++trial) {
            Bytes garbage(magic.begin(), magic.end());
            for (int i = 0; i < 200; ++i) garbage.push_back(static_cast<unsigned char>(rng()));
            std::string path = dir.file("magic_garbage.bin");
            write_bytes(path, garbage);
            require_particle_error(path);
        }
    }
    std::string text = dir.file("text.txt");
    write_text(text, "hello world\n");
    require_particle_error(text, "unknown particle file format");
}

TEST_CASE("gzip damage: truncated, corrupt, bomb", "[io]") {
    TempDir dir("gzbad");
    const std::string bgeo = kShared + "/splashsurf/ParticleData_Fluid_50.bgeo";
    Bytes bytes = read_bytes(bgeo);
    std::string path = dir.file("cut.bgeo");
    // Every truncation of a gzip stream is detected (the trailer carries the length and CRC).
    for (std::size_t length = 1; length < bytes.size(); length += (length < 64 ? 1 : 1237)) {
        write_bytes(path, bytes, length);
        require_particle_error(path);
    }
    write_bytes(path, bytes, bytes.size() - 1);
    require_particle_error(path, "truncated gzip stream");

    // Flipped bytes: a FormatError or, if the flip only hit the gzip header's timestamp, a clean read.
    for (std::size_t at = 0; at < bytes.size(); at += 331) {
        Bytes copy = bytes;
        copy[at] ^= 0x5a;
        write_bytes(path, copy);
        require_clean_outcome(path);
    }
    Bytes corrupt = bytes;
    corrupt[bytes.size() / 2] ^= 0xff;
    write_bytes(path, corrupt);
    require_particle_error(path, "gzip");

    // 100 MiB of zeros compress to about 100 KiB: far beyond the ratio any particle file reaches.
    z_stream zs{};
    REQUIRE(deflateInit2(&zs, 9, Z_DEFLATED, 15 + 16, 9, Z_DEFAULT_STRATEGY) == Z_OK);
    Bytes zeros(1 << 20, 0), bomb(1 << 20);
    std::size_t out_pos = 0;
    for (int chunk = 0; chunk < 100; ++chunk) {
        const bool last = chunk == 99;
        zs.next_in = zeros.data();
        zs.avail_in = static_cast<uInt>(zeros.size());
        int ret = Z_OK;
        do {
            if (out_pos == bomb.size()) bomb.resize(bomb.size() * 2);
            zs.next_out = bomb.data() + out_pos;
            zs.avail_out = static_cast<uInt>(bomb.size() - out_pos);
            ret = deflate(&zs, last ? Z_FINISH : Z_NO_FLUSH);
            out_pos = bomb.size() - zs.avail_out;
        } while (zs.avail_in > 0 || (last && ret != Z_STREAM_END));
    }
    deflateEnd(&zs);
    bomb.resize(out_pos);
    std::string bomb_path = dir.file("bomb.vtk.gz");
    write_bytes(bomb_path, bomb);
    require_particle_error(bomb_path, "decompresses to more than");
}

TEST_CASE("truncated shared files give FormatError", "[io]") {
    TempDir dir("trunc");
    for (const auto& spec : shared_files()) {
        const std::string source = kShared + "/" + spec.path;
        const bool is_bgeo = spec.path.find(".bgeo") != std::string::npos;
        // BGEO files are gzip: truncate the decompressed content (plain BGEO is read too), so that the BGEO parser,
        // not only zlib, sees the damage; every tenth cut is compressed again to go through gunzip as well.
        Bytes bytes = is_bgeo ? gunzip_file(source) : read_bytes(source);
        std::string path = dir.file(is_bgeo ? "cut.bgeo" : "cut.vtk");
        int cuts = 0;
        auto write_cut = [&](std::size_t length) {
            if (is_bgeo && ++cuts % 10 == 0)
                write_bytes(path, gzip(Bytes(bytes.begin(), bytes.begin() + static_cast<std::ptrdiff_t>(length))));
            else
                write_bytes(path, bytes, length);
        };
        INFO(spec.path);

        // Offsets that must fail: every byte of the leading header and of the point data.
        std::size_t points_end;
        if (is_bgeo) {
            std::size_t per_point = 16;
            for (const auto& a : spec.attributes) per_point += 4 * static_cast<std::size_t>(a.components);
            points_end = bytes.size() - 2;  // the points end where the 2 trailing bytes (no groups, no prims) start
            REQUIRE(points_end >= spec.count * per_point);
        } else {
            auto keywords = vtk_keyword_offsets(bytes);
            REQUIRE(keywords.size() >= 3);
            points_end = keywords[1] - 1;  // the newline before CELLS
            // Inside every keyword and just before the next one (in the middle of data): must fail.
            for (std::size_t k = 0; k < keywords.size(); ++k) {
                for (std::size_t cut : {keywords[k] + 2, keywords[k] + 8}) {
                    write_cut(cut);
                    require_particle_error(path);
                }
                if (k > 0) {
                    write_cut(keywords[k] - 3);
                    require_particle_error(path);
                }
            }
            write_cut(bytes.size() - 3);
            require_particle_error(path);
        }
        for (std::size_t length = 1; length < std::min<std::size_t>(points_end, 300); ++length) {
            write_cut(length);
            require_particle_error(path);
        }
        const std::size_t stride = std::max<std::size_t>(997, bytes.size() / 97);
        for (std::size_t length = 300; length < points_end; length += stride) {
            write_cut(length);
            std::string message = require_particle_error(path);
            REQUIRE_THAT(message, Catch::Contains("truncated at byte"));
        }
        // Anywhere else: a FormatError or (at a section boundary) a clean read of the sections before the cut.
        for (std::size_t length = points_end; length < bytes.size(); length += stride + 12) {
            write_cut(length);
            require_clean_outcome(path);
        }
    }
}

TEST_CASE("damaged counts and types in VTK headers give FormatError", "[io]") {
    TempDir dir("counts");
    const std::string bunny = kShared + "/splashsurf/bunny_frame_14_7705_particles.vtk";
    const Bytes bytes = read_bytes(bunny);
    std::string path = dir.file("bunny.vtk");
    struct Case {
        const char* from;
        const char* to;
        const char* expect;
    };
    const Case cases[] = {
        {"POINTS 7706 float", "POINTS 1000000000000 float", "needs 12000000000000 bytes but the file has only 308"},
        {"POINTS 7706 float", "POINTS 9706 float", ""},
        {"POINTS 7706 float", "POINTS 1706 float", ""},
        {"POINTS 7706 float", "POINTS 7706 xyz__", "unknown data type 'xyz__' for POINTS"},
        {"POINTS 7706 float", "POINTS -7706 float", "bad POINTS count"},
        {"POINTS 7706 float", "POINTS 18446744073709551615 float", "impossibly large"},
        {"POINTS 7706 float", "POINTS 7706 double", ""},
        {"POINTS 7706 float", "POINTS 7706 bit", "unsupported data type 'bit'"},
        {"CELLS 7706 15412", "CELLS 7706 95412", ""},
        {"CELLS 7706 15412", "CELLS 7706 15411", ""},
        {"CELL_TYPES 7706", "CELL_TYPES 9999", ""},
        {"POINT_DATA 7706", "POINT_DATA 7705", "does not match POINTS count"},
        {"SCALARS id unsigned_int", "SCALARS id unsigned_xyz", "unknown data type"},
        {"FieldData 1", "FieldData 2", "truncated"},
        {"FieldData 1", "FieldData 99999999999", "FIELD array count"},
        {"velocity 3 7706 float", "velocity 3 7707 float", "has 7707 tuples"},
        {"velocity 3 7706 float", "velocity 0 7706 float", "component count"},
        {"velocity 3 7706 float", "velocity 3000 7706 float", "needs"},
        {"BINARY", "BINORY", "expected ASCII or BINARY"},
        {"DATASET UNSTRUCTURED_GRID", "DATASET STRUCTURED_POINTS", "unsupported DATASET"},
        {"# vtk DataFile", "# vtk DataFoo", "not a legacy VTK file"},
        {"POINT_DATA", "POINT_DOTA", "unknown keyword 'POINT_DOTA'"},
    };
    for (const auto& c : cases) {
        INFO(c.from << " -> " << c.to);
        write_bytes(path, replace_text(bytes, c.from, c.to));
        std::string message = require_particle_error(path, c.expect);
    }

    // The same through ASCII: counts beyond what the remaining text can hold are refused before allocating.
    std::string ascii = dir.file("ascii.vtk");
    write_text(ascii, "# vtk DataFile Version 4.1\nx\nASCII\nDATASET POLYDATA\nPOINTS 1000000000000 float\n0 0 0\n");
    require_particle_error(ascii, "cannot fit");
    write_text(ascii, "# vtk DataFile Version 4.1\nx\nASCII\nDATASET POLYDATA\nPOINTS 2 float\n0 0 0 1 1 zz\n");
    require_particle_error(ascii, "bad value 'zz'");
    write_text(ascii, "# vtk DataFile Version 4.1\nx\nASCII\nDATASET POLYDATA\nPOINTS 3 float\n0.0 0.0 0.0 1.0 1.0 1.0 2.0 2.0\n");
    require_particle_error(ascii, "truncated at byte");
    write_text(ascii, "# vtk DataFile Version 4.1\nx\nASCII\nDATASET POLYDATA\n");
    require_particle_error(ascii, "no POINTS section");
    write_text(ascii, "# vtk DataFile Version 4.1\nx\nASCII\nDATASET POLYDATA\nPOINTS 1 float\n0 0 0\nSCALARS a float\n1\n");
    require_particle_error(ascii, "before any POINT_DATA");

    // Random single-byte damage anywhere in the header region: never a crash, only FormatError or a clean read.
    std::mt19937 rng(11);
    for (int trial = 0; trial < 300; ++trial) {
        Bytes copy = bytes;
        std::size_t at = rng() % 120;
        if (trial % 3 == 0) {
            auto keys = vtk_keyword_offsets(bytes);
            at = keys[rng() % keys.size()] + rng() % 16;
        }
        copy[at] = static_cast<unsigned char>(rng());
        write_bytes(path, copy);
        require_clean_outcome(path);
    }
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

// ---------------------------------------------------------------------------------------------------------------
// Meshes

TEST_CASE("PLY round trip keeps vertices, triangles, normals and attributes", "[io]") {
    TempDir dir("ply");
    TriMesh mesh = make_test_mesh();
    std::string path = dir.file("mesh.ply");
    write_mesh(mesh, path);
    TriMesh back = read_mesh(path);
    require_same_mesh(mesh, back, true);

    std::string header(reinterpret_cast<const char*>(read_bytes(path).data()), 400);
    CHECK_THAT(header, Catch::Contains("format binary_little_endian 1.0"));
    CHECK_THAT(header, Catch::Contains("property float velocity_x\nproperty float velocity_y\nproperty float velocity_z\n"));
    CHECK_THAT(header, Catch::Contains("property float uv_0\nproperty float uv_1\n"));
    CHECK_THAT(header, Catch::Contains("property list uchar int vertex_indices"));

    // Without normals and attributes; and an empty mesh.
    TriMesh bare = mesh;
    bare.normals.clear();
    bare.attributes.clear();
    write_mesh(bare, path);
    require_same_mesh(bare, read_mesh(path), true);
    write_mesh(TriMesh{}, path);
    TriMesh empty = read_mesh(path);
    REQUIRE(empty.vertices.empty());
    REQUIRE(empty.triangles.empty());
}

TEST_CASE("OBJ round trip keeps vertices, triangles and normals", "[io]") {
    TempDir dir("obj");
    TriMesh mesh = make_test_mesh();
    std::string path = dir.file("mesh.obj");
    write_mesh(mesh, path);
    TriMesh back = read_mesh(path);
    require_same_mesh(mesh, back, false);
    REQUIRE(back.attributes.empty());

    TriMesh bare = mesh;
    bare.normals.clear();
    write_mesh(bare, path);
    require_same_mesh(bare, read_mesh(path), false);
}

TEST_CASE("PLY in ASCII and big-endian binary, with polygons and extra elements", "[io]") {
    TriMesh ascii = read_mesh(kTestData + "/io/quad_ascii.ply");
    REQUIRE(ascii.num_vertices() == 5);
    REQUIRE(ascii.triangles == std::vector<int32_t>{0, 1, 2, 0, 2, 3, 0, 1, 4});  // the quad fanned
    REQUIRE(ascii.normals.size() == 15);
    REQUIRE(ascii.normals[2] == 1.0f);
    REQUIRE(ascii.attributes.size() == 2);
    CHECK(ascii.attributes[0].name == "quality");
    CHECK(ascii.attributes[0].values == std::vector<float>{10, 20, 30, 40, 50});
    CHECK(ascii.attributes[1].name == "velocity");
    CHECK(ascii.attributes[1].components == 3);
    CHECK(ascii.attributes[1].values[14] == -1.0f);

    // The same as big-endian binary with mixed types.
    TempDir dir("plybe");
    BigEndianWriter w;
    w.text("ply\r\nformat binary_big_endian 1.0\r\nelement vertex 4\r\nproperty double x\r\nproperty float y\r\n"
           "property int z\r\nproperty short temperature\r\nelement face 1\r\nproperty list uint ushort vertex_index\r\n"
           "end_header\r\n");
    for (int v = 0; v < 4; ++v) {
        w.f64(v * 0.5);
        w.f32(float(v));
        w.u32(static_cast<std::uint32_t>(-v));
        w.u16(static_cast<unsigned>(v * 100));
    }
    w.u32(4);
    for (unsigned i : {3u, 2u, 1u, 0u}) w.u16(i);
    std::string path = dir.file("be.ply");
    write_bytes(path, w.bytes);
    TriMesh be = read_mesh(path);
    REQUIRE(be.vertices == std::vector<float>{0, 0, 0, 0.5f, 1, -1, 1, 2, -2, 1.5f, 3, -3});
    REQUIRE(be.triangles == std::vector<int32_t>{3, 2, 1, 3, 1, 0});
    REQUIRE(be.normals.empty());
    REQUIRE(be.attributes.size() == 1);
    CHECK(be.attributes[0].values == std::vector<float>{0, 100, 200, 300});
}

TEST_CASE("OBJ face forms and negative indices", "[io]") {
    TriMesh m = read_mesh(kTestData + "/io/mixed.obj");
    REQUIRE(m.num_vertices() == 4);
    REQUIRE(m.triangles == std::vector<int32_t>{0, 1, 2, 0, 2, 3, 0, 1, 2, 0, 2, 3, 1, 2, 3});
    REQUIRE(m.normals.empty());  // one face has no normals, so there are no per-vertex normals

    TempDir dir("objn");
    std::string path = dir.file("n.obj");
    write_text(path, "v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0 1\nvn 0 0 -1\nf 1//2 2//2 3//2\n");
    TriMesh n = read_mesh(path);
    REQUIRE(n.normals == std::vector<float>{0, 0, -1, 0, 0, -1, 0, 0, -1});
}

TEST_CASE("VTK mesh output parses", "[io]") {
    TempDir dir("vtkout");
    TriMesh mesh = make_test_mesh();
    std::string path = dir.file("mesh.vtk");
    write_mesh(mesh, path);
    Bytes bytes = read_bytes(path);
    std::string text(bytes.begin(), bytes.end());
    REQUIRE(starts_with(text, "# vtk DataFile Version 4.2\nmeniscus surface mesh\nBINARY\nDATASET POLYDATA\nPOINTS 6 float\n"));
    REQUIRE(text.find("\nPOLYGONS 8 32\n") != std::string::npos);
    REQUIRE(text.find("\nPOINT_DATA 6\nNORMALS normals float\n") != std::string::npos);
    // The particle reader understands POLYDATA: points, normals and attributes come back.
    ParticleData p = read_particles(path);
    REQUIRE(p.positions == mesh.vertices);
    REQUIRE(p.attributes.size() == 4);
    CHECK(p.attributes[0].name == "normals");
    CHECK(p.attributes[0].values == mesh.normals);
    for (int i = 0; i < 3; ++i) {
        CHECK(p.attributes[i + 1].name == mesh.attributes[i].name);
        CHECK(p.attributes[i + 1].components == mesh.attributes[i].components);
        CHECK(p.attributes[i + 1].values == mesh.attributes[i].values);
    }
    // Triangles: decode the POLYGONS block directly.
    std::size_t at = text.find("\nPOLYGONS 8 32\n") + std::strlen("\nPOLYGONS 8 32\n");
    for (int t = 0; t < 8; ++t) {
        auto word = [&](int k) {
            const unsigned char* b = &bytes[at + 16 * t + 4 * k];
            return static_cast<int32_t>((std::uint32_t(b[0]) << 24) | (b[1] << 16) | (b[2] << 8) | b[3]);
        };
        REQUIRE(word(0) == 3);
        for (int k = 0; k < 3; ++k) REQUIRE(word(k + 1) == mesh.triangles[3 * t + k]);
    }
}

TEST_CASE("mesh writing errors", "[io]") {
    TempDir dir("wr");
    TriMesh mesh = make_test_mesh();
    REQUIRE_THROWS_AS(write_mesh(mesh, dir.file("mesh.stl")), InputError);
    try {
        write_mesh(mesh, dir.file("mesh.stl"));
    } catch (const InputError& e) {
        CHECK_THAT(e.what(), Catch::Contains("'.stl'") && Catch::Contains(".ply, .obj, .vtk"));
    }
    std::string no_dir = dir.file("missing/dir/mesh.ply");
    REQUIRE_THROWS_AS(write_mesh(mesh, no_dir), FormatError);
    CHECK_THAT(format_error_of([&] { write_mesh(mesh, no_dir); }), Catch::StartsWith(no_dir));

    TriMesh broken = mesh;
    broken.triangles[4] = 6;
    REQUIRE_THROWS_AS(write_mesh(broken, dir.file("b.ply")), InputError);
    broken = mesh;
    broken.attributes[1].values.pop_back();
    REQUIRE_THROWS_AS(write_mesh(broken, dir.file("b.ply")), InputError);

    if (fs::exists("/dev/full")) {  // a disk that is always full
        for (const char* name : {"full.ply", "full.obj", "full.vtk"}) {
            std::string link = dir.file(name);
            fs::create_symlink("/dev/full", link);
            TriMesh big = mesh;
            for (int i = 0; i < 17; ++i) {  // beyond the writer's buffer, so the failure shows in fwrite too
                big.vertices.insert(big.vertices.end(), big.vertices.begin(), big.vertices.end());
                big.normals.insert(big.normals.end(), big.normals.begin(), big.normals.end());
                for (auto& a : big.attributes) a.values.insert(a.values.end(), a.values.begin(), a.values.end());
            }
            REQUIRE_THROWS_AS(write_mesh(big, link), FormatError);
            CHECK_THAT(format_error_of([&] { write_mesh(mesh, link); }), Catch::StartsWith(link) && Catch::Contains("write error"));
        }
    }
}

TEST_CASE("damaged meshes give FormatError", "[io]") {
    TempDir dir("meshbad");
    TriMesh mesh = make_test_mesh();
    std::string good = dir.file("good.ply");
    write_mesh(mesh, good);
    Bytes bytes = read_bytes(good);
    std::string path = dir.file("cut.ply");
    for (std::size_t length = 1; length < bytes.size(); ++length) {
        write_bytes(path, bytes, length);
        require_mesh_error(path);
    }
    auto replaced = [&](const char* from, const char* to) {
        write_bytes(path, replace_text(bytes, from, to));
        return path;
    };
    require_mesh_error(replaced("element vertex 6", "element vertex 99999999999"), "element 'vertex' count");
    require_mesh_error(replaced("element face 8", "element face 99999999999"), "element 'face' count");
    require_mesh_error(replaced("element face 8", "element face 9"), "truncated");
    require_mesh_error(replaced("element vertex 6", "element vertex 5"));
    require_mesh_error(replaced("property float x", "property flaot x"), "unknown property type");
    require_mesh_error(replaced("binary_little_endian", "binary_middle_endian"), "unknown PLY format");
    require_mesh_error(replaced("end_header", "end_heade"), "");
    // A face referring to a vertex that does not exist.
    Bytes bad_index = bytes;
    bad_index[bytes.size() - 1] = 0x7f;
    write_bytes(path, bad_index);
    require_mesh_error(path, "refers to vertex");
    // Random damage.
    std::mt19937 rng(3);
    for (int trial = 0; trial < 300; ++trial) {
        Bytes copy = bytes;
        copy[rng() % copy.size()] = static_cast<unsigned char>(rng());
        write_bytes(path, copy);
        std::string message = format_error_of([&] { read_mesh(path); });
        if (!message.empty()) REQUIRE(starts_with(message, path));
    }

    std::string obj = dir.file("bad.obj");
    write_text(obj, "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4\n");
    require_mesh_error(obj, "refers to vertex 4");
    write_text(obj, "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 -4\n");
    require_mesh_error(obj, "line 4");
    write_text(obj, "v 0 0 0\nv 1 0 zero\n");
    require_mesh_error(obj, "bad number 'zero'");
    write_text(obj, "v 0 0 0\nf 1 1\n");
    require_mesh_error(obj, "at least 3");
    write_text(obj, "v 0 0 0\nf 1 1 0\n");
    require_mesh_error(obj, "bad vertex index '0'");
    Bytes garbage(3000);
    for (auto& b : garbage) b = static_cast<unsigned char>(rng());
    write_bytes(obj, garbage);
    require_mesh_error(obj);
    REQUIRE_THROWS_AS(read_mesh(dir.path.string()), FormatError);
    REQUIRE_THROWS_AS(read_mesh(dir.file("missing.ply")), FormatError);
    std::string empty = dir.file("empty.obj");
    write_text(empty, "");
    require_mesh_error(empty, "empty file");
    std::string other = dir.file("mesh.stl");
    write_text(other, "solid x\n");
    require_mesh_error(other, "unknown mesh format");
}
