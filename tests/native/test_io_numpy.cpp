// NumPy .npy (header forms, dtypes, refusals) and .npz (zip methods, CRC, the choice of members).
#include <catch2/catch.hpp>
#include <cstring>
#include <string>
#include <utility>
#include <vector>
#include "reader_checks.h"

using namespace meniscus;
using namespace meniscus::test;
namespace fs = std::filesystem;

namespace {

Bytes npy(const std::string& header_dict, const Bytes& data, int major = 1) {
    std::string header = header_dict;
    std::size_t prefix = major == 1 ? 10 : 12;
    while ((prefix + header.size() + 1) % 64) header += ' ';
    header += '\n';
    Bytes out = as_bytes(std::string("\x93NUMPY") + char(major) + char(0));
    if (major == 1) {
        out.push_back(static_cast<unsigned char>(header.size() & 255));
        out.push_back(static_cast<unsigned char>(header.size() >> 8));
    } else {
        for (int k = 0; k < 4; ++k) out.push_back(static_cast<unsigned char>(header.size() >> (8 * k)));
    }
    out.insert(out.end(), header.begin(), header.end());
    out.insert(out.end(), data.begin(), data.end());
    return out;
}

Bytes floats_le(const std::vector<float>& v) {
    Bytes out(4 * v.size());
    std::memcpy(out.data(), v.data(), out.size());  // the test machines are little-endian
    return out;
}

// A zip archive of stored members (what numpy.savez writes, without the zip64 extras).
Bytes zip_stored(const std::vector<std::pair<std::string, Bytes>>& members) {
    Bytes out, directory;
    auto u16 = [](Bytes& b, unsigned v) {
        b.push_back(static_cast<unsigned char>(v));
        b.push_back(static_cast<unsigned char>(v >> 8));
    };
    auto u32 = [&](Bytes& b, unsigned long v) {
        u16(b, static_cast<unsigned>(v & 0xffff));
        u16(b, static_cast<unsigned>(v >> 16));
    };
    for (const auto& [name, data] : members) {
        const unsigned long crc = crc32(0, data.data(), static_cast<uInt>(data.size()));
        const unsigned long offset = out.size();
        u32(out, 0x04034b50);
        u16(out, 20); u16(out, 0); u16(out, 0); u16(out, 0); u16(out, 0);
        u32(out, crc); u32(out, data.size()); u32(out, data.size());
        u16(out, static_cast<unsigned>(name.size())); u16(out, 0);
        out.insert(out.end(), name.begin(), name.end());
        out.insert(out.end(), data.begin(), data.end());
        u32(directory, 0x02014b50);
        u16(directory, 20); u16(directory, 20); u16(directory, 0); u16(directory, 0); u16(directory, 0); u16(directory, 0);
        u32(directory, crc); u32(directory, data.size()); u32(directory, data.size());
        u16(directory, static_cast<unsigned>(name.size())); u16(directory, 0); u16(directory, 0); u16(directory, 0); u16(directory, 0);
        u32(directory, 0); u32(directory, offset);
        directory.insert(directory.end(), name.begin(), name.end());
    }
    const unsigned long cd_offset = out.size();
    out.insert(out.end(), directory.begin(), directory.end());
    u32(out, 0x06054b50);
    u16(out, 0); u16(out, 0); u16(out, static_cast<unsigned>(members.size())); u16(out, static_cast<unsigned>(members.size()));
    u32(out, directory.size()); u32(out, cd_offset); u16(out, 0);
    return out;
}

}  // namespace

TEST_CASE("NumPy: header forms, dtypes and refusals", "[formats]") {
    TempDir dir("npy");
    std::string path = dir.file("a.npy");
    write_bytes(path, npy("{'descr': '<f4', 'fortran_order': False, 'shape': (2, 3), }", floats_le({1, 2, 3, 4, 5, 6}), 2));
    REQUIRE(read_particles(path).positions == std::vector<float>{1, 2, 3, 4, 5, 6});
    write_bytes(path, npy("{\"descr\": \"<i2\", \"shape\": (1L, 3L), \"fortran_order\": False}", Bytes{1, 0, 0xff, 0xff, 3, 0}));
    REQUIRE(read_particles(path).positions == std::vector<float>{1, -1, 3});
    // A record with a position subarray and padding.
    write_bytes(path, npy("{'descr': [('pos', '<f4', (3,)), ('', '|V4'), ('mass', '<f4')], 'fortran_order': False, 'shape': (1,)}",
                          floats_le({1, 2, 3, 0, 9})));
    ParticleData p = read_particles(path);
    REQUIRE(p.positions == std::vector<float>{1, 2, 3});
    REQUIRE(p.attributes.size() == 1);
    CHECK(p.attributes[0].name == "mass");
    CHECK(p.attributes[0].values == std::vector<float>{9});

    write_bytes(path, npy("{'descr': '<f4', 'fortran_order': False, 'shape': (2, 4), }", floats_le(std::vector<float>(8))));
    require_particle_error(path, "shape (2, 4); particle positions need shape (N, 3)");
    for (const char* object : {"|O", "|O8"}) {
        write_bytes(path, npy("{'descr': '" + std::string(object) + "', 'fortran_order': False, 'shape': (2, 3), }", Bytes(48)));
        require_particle_error(path, "object arrays are pickles");
    }
    write_bytes(path, npy("{'descr': '<c8', 'fortran_order': False, 'shape': (2, 3), }", Bytes(48)));
    require_particle_error(path, "unsupported dtype '<c8'");
    write_bytes(path, npy("{'descr': [('a', '<f4')], 'fortran_order': False, 'shape': (1,)}", Bytes(4)));
    require_particle_error(path, "no fields x, y, z");
    write_bytes(path, npy("{'descr': '<f4', 'fortran_order': False, 'shape': (1000000, 3), }", Bytes(12)));
    require_particle_error(path, "array data of shape (1000000, 3)");
    write_bytes(path, npy("{'descr': '<f4', 'fortran_order': False, 'shape': (-1, 3), }", Bytes(12)));
    require_particle_error(path, "not a non-negative integer");
    write_bytes(path, npy("{'descr': '<f4', 'fortran_order': False, 'shape': (99999999999, 99999999999, 99999999999), }", Bytes(12)));
    require_particle_error(path, "impossibly large");
    write_bytes(path, npy("{'descr': '<f4', 'shape': (1, 3)", Bytes(12)));
    require_particle_error(path, "bad .npy header");
    Bytes v9 = npy("{'descr': '<f4', 'fortran_order': False, 'shape': (1, 3), }", Bytes(12));
    v9[6] = 9;
    write_bytes(path, v9);
    require_particle_error(path, "format version 9.0");
}

TEST_CASE("NumPy .npz: zip methods, CRC and member choice", "[formats]") {
    TempDir dir("npz");
    std::string path = dir.file("a.npz");
    Bytes zip = read_bytes(kFormats + "/dam26.npz");
    // Central directory entries start with PK\1\2; the method is at +10, the flags at +8.
    auto central = [&](const Bytes& z) {
        std::vector<std::size_t> at;
        for (std::size_t i = 0; i + 4 <= z.size(); ++i)
            if (z[i] == 'P' && z[i + 1] == 'K' && z[i + 2] == 1 && z[i + 3] == 2) at.push_back(i);
        return at;
    };
    auto entries = central(zip);
    REQUIRE(entries.size() == 3);
    Bytes bad = zip;
    bad[entries[0] + 10] = 12;
    write_bytes(path, bad);
    require_particle_error(path, "compression method 12 (bzip2)");
    bad = zip;
    bad[entries[1] + 8] |= 1;
    write_bytes(path, bad);
    require_particle_error(path, "encrypted");
    bad = zip;
    bad[entries[0] - 1000] ^= 0x40;  // a byte of the last member's data
    write_bytes(path, bad);
    require_particle_error(path, "CRC-32 mismatch");
    write_bytes(path, Bytes(zip.begin(), zip.begin() + 70000));
    require_particle_error(path, "end-of-central-directory");

    // Archives without positions, or with nothing but other files.
    write_bytes(path, zip_stored({{"time.npy", npy("{'descr': '<f8', 'fortran_order': False, 'shape': (), }", Bytes(8))},
                                  {"v.npy", npy("{'descr': '<f4', 'fortran_order': False, 'shape': (2, 2), }", Bytes(16))}}));
    require_particle_error(path, "no particle positions in the .npz archive: expected an (N, 3) member");
    require_particle_error(path, "time (), v (2, 2)");
    write_bytes(path, zip_stored({{"readme.txt", as_bytes("hello")}}));
    require_particle_error(path, "no .npy members");
    // Positions chosen by name over an earlier (N, 3) member; members of another length left out.
    write_bytes(path, zip_stored({{"velocity.npy", npy("{'descr': '<f4', 'fortran_order': False, 'shape': (1, 3), }", floats_le({7, 8, 9}))},
                                  {"pos.npy", npy("{'descr': '<f4', 'fortran_order': False, 'shape': (1, 3), }", floats_le({1, 2, 3}))},
                                  {"box.npy", npy("{'descr': '<f4', 'fortran_order': False, 'shape': (2, 3), }", Bytes(24))}}));
    ParticleData p = read_particles(path);
    REQUIRE(p.positions == std::vector<float>{1, 2, 3});
    REQUIRE(p.attributes.size() == 1);
    CHECK(p.attributes[0].name == "velocity");
    CHECK(p.attributes[0].values == std::vector<float>{7, 8, 9});
}

TEST_CASE("NumPy: zero-length subarray fields are skipped", "[formats]") {
    // A fuzzer finding: ('velocity', '>f4', (0,)) made an attribute of 0 components. Such a field holds no values.
    TempDir dir("npy_zero");
    std::string path = dir.file("a.npy");
    const Bytes record = floats_le({1, 2, 3, 4});
    const std::string header = "{'descr': [('x', '<f4'), ('y', '<f4'), ('z', '<f4'), ('velocity', '>f4', (0,)), ('mass', '<f4')], "
                               "'fortran_order': False, 'shape': (1,)}";
    write_bytes(path, npy(header, record));
    ParticleData p = read_particles(path);
    REQUIRE(p.positions == std::vector<float>{1, 2, 3});
    REQUIRE(p.attributes.size() == 1);
    CHECK(p.attributes[0].name == "mass");
    CHECK(p.attributes[0].values == std::vector<float>{4});
    // The same record as a structured .npz member next to separate positions.
    path = dir.file("a.npz");
    write_bytes(path, zip_stored({{"positions.npy", npy("{'descr': '<f4', 'fortran_order': False, 'shape': (1, 3), }", floats_le({1, 2, 3}))},
                                  {"extra.npy", npy(header, record)}}));
    p = read_particles(path);
    REQUIRE(p.attributes.size() == 4);
    for (const auto& a : p.attributes) CHECK(a.components == 1);
    CHECK(p.attributes[3].name == "extra.mass");
}
