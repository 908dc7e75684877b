// OpenVDB point data grids read without the OpenVDB library, and the Blosc decoder under them. The sample is a
// Blender 3.4 Mantaflow bake (tests/data/mantaflow: resolution 8, frame 1; a half-float velocity grid and a point
// grid with half-float offsets in LZ4 Blosc pages); tests/python/test_mantaflow.py compares larger bakes with the
// UNI cache of the same simulation.
#include <catch2/catch.hpp>
#include <algorithm>
#include <cstring>
#include <string>
#include <vector>

#include "io/blosc.h"
#include "reader_checks.h"

using namespace meniscus;
using namespace meniscus::test;

namespace {

const std::string kCache = kTestData + "/mantaflow/cache";
const std::string kVdb = kCache + "/data/fluid_data_0001.vdb";

Bytes blosc_frame(unsigned flags, unsigned type_size, std::size_t nbytes, const Bytes& stream) {
    Bytes f = {2, 1, static_cast<unsigned char>(flags), static_cast<unsigned char>(type_size)};
    auto put = [&](std::uint32_t v) {
        for (int k = 0; k < 4; ++k) f.push_back(static_cast<unsigned char>(v >> (8 * k)));
    };
    put(static_cast<std::uint32_t>(nbytes));
    put(static_cast<std::uint32_t>(nbytes));  // one block
    put(static_cast<std::uint32_t>(16 + 4 + 4 + stream.size()));
    put(20);  // the block's start
    put(static_cast<std::uint32_t>(stream.size()));
    f.insert(f.end(), stream.begin(), stream.end());
    return f;
}

std::string blosc_outcome(const Bytes& frame, std::size_t expected, Bytes* out = nullptr) {
    Bytes buffer(expected);
    const std::string e = format_error_of([&] { io_detail::blosc_decompress("x.vdb", frame.data(), frame.size(), buffer.data(), expected, "test"); });
    if (out) *out = buffer;
    return e;
}

}  // namespace

TEST_CASE("Blosc frames: BloscLZ, LZ4, byte shuffle and stored frames decode, damage is refused", "[io][vdb]") {
    Bytes out;
    // BloscLZ: 3 literals "abc", then a match of 5 at distance 3 (ctrl 0x60, distance byte 2).
    CHECK(blosc_outcome(blosc_frame(0x10, 1, 8, {0x02, 'a', 'b', 'c', 0x60, 0x02}), 8, &out) == "");
    CHECK(as_text(out) == "abcabcab");
    // LZ4: "abc", a match of 5 at offset 3, then the last literals "XY".
    CHECK(blosc_outcome(blosc_frame(0x10 | 0x20, 1, 10, {0x31, 'a', 'b', 'c', 3, 0, 0x20, 'X', 'Y'}), 10, &out) == "");
    CHECK(as_text(out) == "abcabcabXY");
    // Byte shuffle of two 4-byte values, LZ4 literals only.
    CHECK(blosc_outcome(blosc_frame(0x1 | 0x10 | 0x20, 4, 8, {0x80, 4, 8, 3, 7, 2, 6, 1, 5}), 8, &out) == "");
    CHECK(out == Bytes{4, 3, 2, 1, 8, 7, 6, 5});
    // Stored (memcpyed).
    Bytes stored = {2, 1, 0x2, 1, 3, 0, 0, 0, 3, 0, 0, 0, 19, 0, 0, 0, 'x', 'y', 'z'};
    CHECK(blosc_outcome(stored, 3, &out) == "");
    CHECK(as_text(out) == "xyz");

    // The fuzzer's finding: an empty stored frame into no output (a null buffer) copied nothing from nowhere.
    const Bytes empty = {2, 1, 0x2, 1, 0, 0, 0, 0, 0, 0, 0, 0, 16, 0, 0, 0};
    CHECK(format_error_of([&] { io_detail::blosc_decompress("x.vdb", empty.data(), empty.size(), nullptr, 0, "test"); }) == "");

    CHECK_THAT(blosc_outcome(blosc_frame(0x10, 1, 8, {0x02, 'a', 'b', 'c', 0x60, 0x05}), 8), Catch::Contains("reaches before the start"));
    CHECK_THAT(blosc_outcome(blosc_frame(0x10 | 0x20, 1, 10, {0x31, 'a', 'b', 'c', 3, 0}), 10), Catch::Contains("without its last literals"));
    CHECK_THAT(blosc_outcome(blosc_frame(0x10, 1, 8, {0x02, 'a', 'b', 'c', 0x60, 0x02}), 9), Catch::Contains("where 9 are expected"));
    CHECK_THAT(blosc_outcome(blosc_frame(0x10 | 0x4, 1, 8, {0x02, 'a'}), 8), Catch::Contains("bit-shuffle is not supported"));
    CHECK_THAT(blosc_outcome(blosc_frame(0x10 | (4 << 5), 1, 8, {0x02, 'a'}), 8), Catch::Contains("Zstd is not supported"));
    Bytes short_frame = blosc_frame(0x10, 1, 8, {0x02, 'a', 'b', 'c', 0x60, 0x02});
    short_frame.pop_back();
    CHECK_THAT(blosc_outcome(short_frame, 8), Catch::Contains("its header says 30 bytes, the frame has 29"));
}

TEST_CASE("OpenVDB points from Mantaflow's data cache are placed like its UNI particles", "[io][vdb]") {
    ParticleData p = read_particles(kVdb);
    REQUIRE(p.size() == 314);
    REQUIRE(p.fluid_domain.has_value());
    CHECK(p.fluid_domain->resolution == std::array<int, 3>{8, 8, 6});
    REQUIRE(p.attributes.size() == 1);
    CHECK(p.attributes[0].name == "velocity");
    for (std::size_t i = 0; i < p.size(); ++i) {  // inside the 2 x 2 x 1.5 m domain on the floor at z = 0
        CHECK(std::abs(p.positions[3 * i]) < 1.0f);
        CHECK(std::abs(p.positions[3 * i + 1]) < 1.0f);
        CHECK((p.positions[3 * i + 2] > 0.0f && p.positions[3 * i + 2] < 1.5f));
    }

    // Outside a Mantaflow cache (Houdini's VDB points) the file's own world space and names stay.
    TempDir dir("vdb");
    const std::string alone = dir.file("points.vdb");
    fs::copy_file(kVdb, alone);
    ParticleData raw = read_particles(alone);
    REQUIRE(raw.size() == p.size());
    CHECK_FALSE(raw.fluid_domain.has_value());
    REQUIRE(raw.attributes.size() == 1);
    CHECK(raw.attributes[0].name == "particles_velocity");
    for (std::size_t i = 0; i < p.size(); ++i) {  // Mantaflow's VDB world: grid cells x 0.25 m from the grid corner
        CHECK(raw.positions[3 * i] - 1.0f == Approx(p.positions[3 * i]).margin(1e-5));
        CHECK(raw.positions[3 * i + 2] == Approx(p.positions[3 * i + 2]).margin(1e-5));
    }

    // Named as Mantaflow names its data, but without the cache's config: refused, naming the config.
    fs::create_directories(dir.path / "data");
    const std::string orphan = (dir.path / "data" / "fluid_data_0001.vdb").string();
    fs::copy_file(kVdb, orphan);
    require_particle_error(orphan, "config_0001.uni, which does not exist");
}

TEST_CASE("damaged OpenVDB files give a FormatError naming the file, never a crash", "[io][vdb]") {
    const Bytes good = read_bytes(kVdb);
    TempDir dir("vdbdamage");
    const std::string path = dir.file("points.vdb");
    // Every truncation point in the headers, then every 97th byte.
    for (std::size_t cut = 1; cut < good.size(); cut += cut < 2048 ? 1 : 97) {
        write_bytes(path, good, cut);
        require_particle_error(path);
    }
    // A changed byte anywhere: a clean refusal, or particles whose arrays agree.
    for (std::size_t at = 0; at < good.size(); at += at < 2048 ? 1 : 31) {
        Bytes bad = good;
        bad[at] ^= 0x5a;
        write_bytes(path, bad);
        ParticleData p;
        const std::string message = outcome(path, &p);
        INFO("byte " << at << ": " << message);
        if (message.empty())
            require_consistent(p);
        else
            REQUIRE(starts_with(message, path));
    }
    Bytes no_points = good;
    const std::string type = "Tree_ptdataidx32";
    auto where = std::search(no_points.begin(), no_points.end(), type.begin(), type.end());
    REQUIRE(where != no_points.end());
    *(where + 5) = 'X';  // "Tree_XtdataIdx32...": an unknown grid type, skipped
    write_bytes(path, no_points);
    require_particle_error(path, "holds no OpenVDB point data grid (only velocity (Tree_vec3s_5_4_3), particles (Tree_Xtdataidx32_5_4_3))");
}

namespace {

// A minimal OpenVDB file with one point grid of one leaf (at voxel origin (8, 16, 0)), written the way OpenVDB
// lays it out, for the variants the Blender sample does not show: no compression or zlib (unpaged arrays), Blosc
// with stored pages, float and fixed-point positions, a uniform array, a translated transform.
struct VdbWriter {
    Bytes b;
    void u8(unsigned v) { b.push_back(static_cast<unsigned char>(v)); }
    void u16(unsigned v) { u8(v & 0xff), u8(v >> 8); }
    void u32(std::uint32_t v) { for (int k = 0; k < 4; ++k) u8((v >> (8 * k)) & 0xff); }
    void u64(std::uint64_t v) { for (int k = 0; k < 8; ++k) u8((v >> (8 * k)) & 0xff); }
    void f32(float f) { std::uint32_t u; std::memcpy(&u, &f, 4); u32(u); }
    void f64(double d) { std::uint64_t u; std::memcpy(&u, &d, 8); u64(u); }
    void str(const std::string& s) { u32(static_cast<std::uint32_t>(s.size())); b.insert(b.end(), s.begin(), s.end()); }
    void bytes(const Bytes& d) { b.insert(b.end(), d.begin(), d.end()); }
};

struct VdbAttribute {
    std::string name, type, codec;
    Bytes values;  // stored values of all points (or one, uniform)
    bool uniform = false;
};

// Node values as OpenVDB's readData stores them under `compression`: raw, or an int64 size and a zlib stream or a
// (stored) Blosc frame.
void node_values(VdbWriter& w, std::size_t count, std::uint32_t compression) {
    w.u8(6);  // all values, no mask
    const Bytes zeros(count * 4, 0);
    if (compression == 0) return w.bytes(zeros);
    if (compression == 1) {
        const Bytes z = deflate_bytes(zeros, 15);
        w.u64(z.size());
        return w.bytes(z);
    }
    w.u64(16 + zeros.size());
    w.bytes({2, 1, 0x2, 4});
    w.u32(static_cast<std::uint32_t>(zeros.size()));
    w.u32(static_cast<std::uint32_t>(zeros.size()));
    w.u32(static_cast<std::uint32_t>(16 + zeros.size()));
    w.bytes(zeros);
}

// with_leaf false: a tree without leaves (a root with no children) that still declares the attributes' passes.
Bytes make_vdb(std::uint32_t compression, const std::vector<std::uint32_t>& voxel_of_point, const std::vector<VdbAttribute>& attributes,
               bool with_leaf = true) {
    VdbWriter w;
    w.u64(0x56444220), w.u32(224), w.u32(10), w.u32(0), w.u8(1);
    w.bytes(as_bytes("00000000-0000-0000-0000-000000000000"));
    w.u32(0), w.u32(1);  // no file metadata, one grid
    w.str("points"), w.str("Tree_ptdataidx32_5_4_3"), w.str("");
    const std::size_t offsets = w.b.size();
    w.u64(0), w.u64(0), w.u64(0);
    const std::size_t grid_pos = w.b.size();
    w.u32(compression), w.u32(0);
    w.str("UniformScaleTranslateMap");
    for (double t : {10.0, 20.0, 30.0}) w.f64(t);
    for (int k = 0; k < 15; ++k) w.f64(0.5);  // scale (then the derived values, not used)
    w.u32(1), w.u32(0), w.u32(0), w.u32(with_leaf ? 1 : 0);  // one buffer, background, no tiles, one child (or none)
    if (with_leaf) {
        w.u32(0), w.u32(0), w.u32(0);
        Bytes mask5(4096, 0), mask4(512, 0);
        mask5[0] = 1;  // child 0 of the 32^3 node: origin + 0
        mask4[(1 * 256 + 2 * 16) / 8] = 1 << ((1 * 256 + 2 * 16) % 8);  // child (1, 2, 0) of the 16^3 node: (8, 16, 0)
        w.bytes(mask5), w.bytes(Bytes(4096, 0)), node_values(w, 32768, compression);
        w.bytes(mask4), w.bytes(Bytes(512, 0)), node_values(w, 4096, compression);
        w.bytes(Bytes(64, 0xff));  // the leaf's value mask
    }
    const std::size_t block_pos = w.b.size();
    const bool paged = compression == 4;
    w.u16(static_cast<unsigned>(4 + 2 * attributes.size()));
    if (with_leaf) {
        w.u16(0xffff);
        w.u8(1), w.u64(attributes.size());
        for (const auto& a : attributes) w.str(a.type), w.str(a.codec);
        for (std::size_t k = 0; k < attributes.size(); ++k) w.str(attributes[k].name), w.u64(k);
        w.u64(0), w.u32(0);  // no groups, no metadata
        for (const auto& a : attributes) {
            w.u64(6 + a.values.size()), w.u8(0), w.u8((a.uniform ? 2 : 0) | (paged ? 8 : 0));
            w.u32(static_cast<std::uint32_t>(a.uniform ? 1 : voxel_of_point.size()));
        }
        if (paged)
            for (const auto& a : attributes) w.u32(static_cast<std::uint32_t>(-static_cast<std::int32_t>(a.values.size())));  // stored pages
        w.bytes(Bytes(64, 0xff)), w.u16(0xffff);
        for (std::uint32_t v = 0, p = 0; v < 512; ++v) {
            while (p < voxel_of_point.size() && voxel_of_point[p] == v) ++p;
            w.u32(p);
        }
        for (const auto& a : attributes) {
            if (!paged && !a.uniform) w.u8(0);
            w.bytes(a.values);
        }
    }
    const std::size_t end_pos = w.b.size();
    for (int k = 0; k < 8; ++k) {
        w.b[offsets + k] = static_cast<unsigned char>(grid_pos >> (8 * k));
        w.b[offsets + 8 + k] = static_cast<unsigned char>(block_pos >> (8 * k));
        w.b[offsets + 16 + k] = static_cast<unsigned char>(end_pos >> (8 * k));
    }
    return w.b;
}

template <class T>
Bytes stored(const std::vector<T>& values) {
    Bytes out(values.size() * sizeof(T));
    std::memcpy(out.data(), values.data(), out.size());
    return out;
}

}  // namespace

TEST_CASE("OpenVDB points: compression, codecs, uniform arrays and transforms", "[io][vdb]") {
    TempDir dir("vdbvariants");
    const std::string path = dir.file("points.vdb");
    // Three points: voxel (0, 0, 0) twice, voxel (1, 2, 3) = offset 64 + 16 + 3 once.
    const std::vector<std::uint32_t> voxels = {0, 0, 83};
    const std::vector<float> offsets = {0.0f, 0.0f, 0.0f, 0.25f, -0.5f, 0.125f, -0.25f, 0.5f, 0.0f};
    const std::vector<std::array<double, 3>> expect = {
        {10 + 0.5 * 8, 20 + 0.5 * 16, 30.0}, {10 + 0.5 * 8.25, 20 + 0.5 * 15.5, 30 + 0.5 * 0.125},
        {10 + 0.5 * 8.75, 20 + 0.5 * 18.5, 30 + 0.5 * 3}};
    for (std::uint32_t compression : {0u, 1u, 4u}) {
        INFO("compression " << compression);
        const std::vector<std::int32_t> ids = {7, 8, 9};
        write_bytes(path, make_vdb(compression, voxels,
                                   {{"P", "vec3s", "null", stored(offsets)},
                                    {"id", "int32", "null", stored(ids)},
                                    {"density", "float", "null", stored(std::vector<float>{1000.0f}), true}}));
        ParticleData p = read_particles(path);
        REQUIRE(p.size() == 3);
        for (std::size_t i = 0; i < 3; ++i)
            for (int k = 0; k < 3; ++k) CHECK(p.positions[3 * i + k] == Approx(expect[i][k]).margin(1e-6));
        REQUIRE(p.attributes.size() == 2);
        CHECK(p.attributes[0].name == "id");
        CHECK(p.attributes[0].integral);
        CHECK(p.attributes[0].values == std::vector<float>{7, 8, 9});
        CHECK(p.attributes[1].name == "density");
        CHECK(p.attributes[1].values == std::vector<float>{1000, 1000, 1000});
    }
    // Fixed-point offsets: stored / 65535 - 0.5 (and / 255 - 0.5).
    const std::vector<std::uint16_t> fixed16 = {32768, 32768, 32768, 49151, 0, 40959, 16384, 65535, 32768};
    write_bytes(path, make_vdb(4, voxels, {{"P", "vec3s", "fxpt16", stored(fixed16)}}));
    ParticleData p = read_particles(path);
    REQUIRE(p.size() == 3);
    CHECK(p.positions[3] == Approx(expect[1][0]).margin(1e-4));
    CHECK(p.positions[7] == Approx(expect[2][1]).margin(1e-4));
    const std::vector<std::uint8_t> fixed8 = {128, 128, 128, 191, 0, 159, 64, 255, 128};
    write_bytes(path, make_vdb(0, voxels, {{"P", "vec3s", "fxpt8", stored(fixed8)}}));
    p = read_particles(path);
    CHECK(p.positions[7] == Approx(expect[2][1]).margin(1e-2));

    // Refusals: positions in a codec we do not decode, no P at all, an attribute length that disagrees.
    write_bytes(path, make_vdb(0, voxels, {{"P", "vec3s", "uvec", stored(std::vector<std::uint16_t>{1, 2, 3})}}));
    require_particle_error(path, "positions of type 'vec3s' with codec 'uvec' are not supported");
    write_bytes(path, make_vdb(0, voxels, {{"Q", "vec3s", "null", stored(offsets)}}));
    require_particle_error(path, "has no position attribute 'P'");
    write_bytes(path, make_vdb(0, {0, 0}, {{"P", "vec3s", "null", stored(offsets)}}));
    require_particle_error(path, "36 bytes for 2 values of 12 bytes");

    // A tree without leaves declares passes for attributes it never describes: no points (this read the empty list of
    // attribute descriptions out of bounds).
    write_bytes(path, make_vdb(0, {}, {{"P", "vec3s", "null", {}}, {"id", "int32", "null", {}}}, false));
    CHECK(read_particles(path).size() == 0);
}
