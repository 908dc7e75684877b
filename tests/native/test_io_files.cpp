// Reading particle files in general: every shared frame and converted sample, the choice of reader by content
// (under any name, through gzip), non-ASCII paths, and damaged, truncated, empty, missing and garbage files.
#include <catch2/catch.hpp>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <random>
#include <set>
#include <string>
#include <vector>

#include "base/platform.h"
#include "reader_checks.h"

using namespace meniscus;
using namespace meniscus::test;
namespace fs = std::filesystem;

namespace {

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

struct Sample {
    const char* file;
    bool id, velocity;
    const char* velocity_name = "velocity";
};

const Sample kSamples[] = {
    {"dam26_ascii.vtu", true, true},       {"dam26_base64_be.vtp", true, true}, {"dam26_appended_raw.vtu", true, true},
    {"dam26_zlib_base64.vtu", true, true}, {"dam26_binary.ply", true, true},    {"dam26.xyz", false, false},
    {"dam26.npy", false, false},           {"dam26.npz", true, true},           {"dam26_compressed.npz", true, true},
    {"dam26.csv", true, true},             {"dam26_houdini.bgeo.gz", true, true, "v"},
};

}  // namespace

TEST_CASE("every shared particle file reads with its count and attributes", "[io]") {
    for (const auto& spec : shared_files()) {
        ParticleData p = read_particles(kShared + "/" + spec.path);
        check_particles(p, spec);
    }
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

TEST_CASE("every converted sample reads exactly like the shared VTK frame", "[formats]") {
    REQUIRE(reference().size() == 4732);
    for (const auto& s : kSamples) {
        INFO(s.file);
        require_same(read_particles(kFormats + "/" + s.file), 4732, s.id, s.velocity, s.velocity_name);
    }
}

TEST_CASE("samples are recognised by content under another name and through gzip", "[formats]") {
    TempDir dir("detect");
    for (const auto& s : kSamples) {
        INFO(s.file);
        Bytes bytes = read_bytes(kFormats + "/" + s.file);
        const bool raw_xyz = std::string(s.file) == "dam26.xyz";  // raw floats have no magic: only the extension says it
        std::string renamed = dir.file("frame_0001.dat");
        write_bytes(renamed, bytes);
        if (raw_xyz)
            require_particle_error(renamed, "unknown particle file format");
        else
            require_same(read_particles(renamed), 4732, s.id, s.velocity, s.velocity_name);
        // gzip around any format (the samples that are gzip already are not wrapped twice); the inner extension still
        // counts for XYZ.
        if (bytes[0] == 0x1f) continue;
        std::string gz = dir.file(std::string(s.file) + ".gz");
        write_bytes(gz, gzip(bytes));
        require_same(read_particles(gz), 4732, s.id, s.velocity, s.velocity_name);
    }
}

TEST_CASE("PLY, NumPy, XYZ and CSV variants", "[formats]") {
    const std::string v = kFormats + "/variants/";
    require_same(read_particles(v + "ascii.ply"), 5, true, true);
    require_same(read_particles(v + "binary_be.ply"), 5, true, true);
    require_same(read_particles(v + "f8_fortran.npy"), 5, false, false);
    require_same(read_particles(v + "f4_big_endian.npy"), 5, false, false);
    require_same(read_particles(v + "text.xyz"), 5, false, false);
    require_same(read_particles(v + "structured.npy"), 5, true, true);

    // float16 keeps about 3 decimal digits.
    ParticleData half = read_particles(v + "f2.npy");
    REQUIRE(half.size() == 5);
    for (std::size_t i = 0; i < 15; ++i) CHECK(half.positions[i] == Approx(reference().positions[i]).epsilon(1e-3).margin(1e-4));

    // Separate x, y, z members; the scalar "time" member is not per-particle data and is left out.
    ParticleData members = read_particles(v + "xyz_members.npz");
    require_same(members, 5, true, false);

    ParticleData csv = read_particles(v + "semicolon.csv");
    REQUIRE(std::equal(csv.positions.begin(), csv.positions.end(), reference().positions.begin()));
    REQUIRE(csv.attributes.size() == 1);
    CHECK(csv.attributes[0].name == "density");
    CHECK(csv.attributes[0].values == std::vector<float>(5, 1000.5f));
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
        REQUIRE(read_mesh(path).vertices == mesh.vertices);
    }
    // Errors name the file as the user spelled it.
    const std::string missing = folder + "/missing_\xc3\xa9.vtk";
    REQUIRE_THROWS_WITH(read_particles(missing), Catch::StartsWith(missing));
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

TEST_CASE("particles written as PLY, XYZ and VTK read back; an attribute of the wrong size is refused by name", "[io]") {
    TempDir dir("write_particles");
    ParticleData p;
    p.positions = {0.f, 0.f, 0.f, 1.f, 2.f, 3.f, -1.f, 0.5f, 2.f};
    p.attributes.push_back({"density", 1, {1000.f, 998.f, 1002.f}});
    p.attributes.push_back({"velocity", 3, {1.f, 0.f, 0.f, 0.f, 1.f, 0.f, 0.f, 0.f, 1.f}});
    for (const char* ext : {".ply", ".vtk", ".xyz"}) {
        const std::string path = dir.file(std::string("particles") + ext);
        write_particles(p, path);
        const ParticleData back = read_particles(path);
        CHECK(back.positions == p.positions);
        if (std::string(ext) != ".xyz") {  // XYZ holds positions only
            const Attribute* velocity = find_attribute(back.attributes, "velocity");
            REQUIRE(velocity != nullptr);
            CHECK(velocity->values == p.attributes[1].values);
        }
    }
    p.attributes[1].values.pop_back();
    try {
        write_particles(p, dir.file("bad.ply"));
        FAIL("an attribute with a value missing was written");
    } catch (const InputError& e) {
        const std::string message = e.what();
        CHECK(message.find("bad.ply") != std::string::npos);
        CHECK(message.find("particle attribute 'velocity' has 8 values with 3 components, expected one tuple per particle (3)") !=
              std::string::npos);
    }
}
