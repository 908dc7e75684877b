// OpenVDB point data grids read without the OpenVDB library, and the Blosc decoder under them. The sample is a
// Blender 3.4 Mantaflow bake (tests/data/mantaflow: resolution 8, frame 1; a half-float velocity grid and a point
// grid with half-float offsets in LZ4 Blosc pages); tests/python/test_mantaflow.py compares larger bakes with the
// UNI cache of the same simulation.
#include <catch2/catch.hpp>
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

TEST_CASE("Blosc frames: BloscLZ, LZ4, byte shuffle, stored; damage refused", "[io][vdb]") {
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
    for (std::size_t at = 0; at < good.size(); at += at < 2048 ? 1 : 13) {
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
