// Tests of the particle formats beyond legacy VTK and BGEO: VTK XML (.vtu/.vtp), PLY, XYZ, NumPy .npy/.npz, CSV,
// and the choice of reader by content. The samples in tests/data/formats/ are the shared double dam break frame 26
// converted by tests/data/formats/make_samples.py; every one must read exactly like the original VTK file.
#include <zlib.h>

#include <catch2/catch.hpp>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "base/errors.h"
#include "io/io.h"
#include "test_files.h"

using namespace meniscus;
using namespace meniscus::test;
namespace fs = std::filesystem;

namespace {

const std::string kShared = MENISCUS_SHARED_DATA;
const std::string kFormats = std::string(MENISCUS_TEST_DATA) + "/formats";
const std::string kSource = kShared + "/splashsurf/double_dam_break_frame_26_4732_particles.vtk";

std::string as_text(const Bytes& b) { return std::string(b.begin(), b.end()); }
Bytes as_bytes(const std::string& s) { return Bytes(s.begin(), s.end()); }

std::string error_of(const std::string& path) {
    try {
        read_particles(path);
    } catch (const FormatError& e) {
        return e.what();
    }
    return "";
}

// read_particles must fail with a FormatError that starts with the path and contains `expect`.
void require_error(const std::string& path, const std::string& expect) {
    std::string message = error_of(path);
    INFO("path: " << path << "\nmessage: " << message);
    REQUIRE(!message.empty());
    REQUIRE(message.rfind(path, 0) == 0);
    REQUIRE_THAT(message, Catch::Contains(expect));
}

const ParticleData& reference() {
    static const ParticleData data = read_particles(kSource);
    return data;
}

// The first n particles of the reference frame, with the given attributes (id and/or velocity, which Houdini
// calls "v").
void require_same(const ParticleData& p, std::size_t n, bool with_id, bool with_velocity, const char* velocity_name = "velocity") {
    const ParticleData& ref = reference();
    REQUIRE(p.size() == n);
    REQUIRE(std::equal(p.positions.begin(), p.positions.end(), ref.positions.begin()));
    std::size_t expected = std::size_t(with_id) + std::size_t(with_velocity);
    REQUIRE(p.attributes.size() == expected);
    if (with_id) {
        const Attribute* id = find_attribute(p.attributes, "id");
        REQUIRE(id);
        REQUIRE(id->components == 1);
        REQUIRE(std::equal(id->values.begin(), id->values.end(), ref.attributes[0].values.begin()));
        REQUIRE(id->values.size() == n);
    }
    if (with_velocity) {
        const Attribute* v = find_attribute(p.attributes, std::string(velocity_name));
        REQUIRE(v);
        REQUIRE(v->components == 3);
        REQUIRE(v->values.size() == 3 * n);
        REQUIRE(std::equal(v->values.begin(), v->values.end(), ref.attributes[1].values.begin()));
    }
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
            require_error(renamed, "unknown particle file format");
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

TEST_CASE("every VTK XML encoding variant reads the same 5 particles", "[formats]") {
    int files = 0;
    for (const auto& entry : fs::directory_iterator(kFormats + "/variants")) {
        const std::string ext = entry.path().extension().string();
        if (ext != ".vtu" && ext != ".vtp") continue;
        INFO(entry.path().filename().string());
        require_same(read_particles(entry.path().string()), 5, true, true);
        ++files;
    }
    REQUIRE(files == 26);  // ascii + 3 binary modes x zlib or not x 2 header types x 2 byte orders + PolyData
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

// ---------------------------------------------------------------------------------------------------------------
// VTK XML details

namespace {

std::string vtu(const std::string& pieces, const std::string& root_attributes = "") {
    return "<?xml version=\"1.0\"?>\n<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" byte_order=\"LittleEndian\"" +
           root_attributes + ">\n<UnstructuredGrid>\n" + pieces + "</UnstructuredGrid>\n</VTKFile>\n";
}

std::string piece(int n, const std::string& points, const std::string& point_data) {
    return "<Piece NumberOfPoints=\"" + std::to_string(n) + "\" NumberOfCells=\"0\">\n<PointData>\n" + point_data +
           "</PointData>\n<Points>\n<DataArray type=\"Float32\" NumberOfComponents=\"3\" format=\"ascii\">" + points +
           "</DataArray>\n</Points>\n<Cells>\n<DataArray type=\"Int64\" Name=\"connectivity\" format=\"ascii\"></DataArray>\n"
           "</Cells>\n</Piece>\n";
}

}  // namespace

TEST_CASE("VTK XML: pieces, skipped arrays, comments, entities and information keys", "[formats]") {
    TempDir dir("vtu");
    std::string path = dir.file("p.vtu");
    std::string data_a =
        "<!-- a comment with <DataArray> inside -->\n"
        "<DataArray type=\"Float64\" Name=\"rho &amp; co\" format=\"ascii\">\n"
        "  <InformationKey name=\"L2_NORM_RANGE\" location=\"vtkDataArray\" length=\"2\"><Value index=\"0\">99</Value></InformationKey>\n"
        "  1.5 2.5</DataArray>\n"
        "<DataArray type=\"String\" Name=\"label\" format=\"ascii\">102 111 0 98 0</DataArray>\n"
        "<DataArray type=\"Int8\" Name=\"flag\" NumberOfComponents=\"2\" format=\"ascii\"><![CDATA[-1 2]]> 3 4</DataArray>\n";
    std::string data_b =
        "<DataArray type=\"Int8\" Name=\"flag\" NumberOfComponents=\"2\" format=\"ascii\">5 6</DataArray>\n"
        "<DataArray type=\"Float64\" Name=\"rho &amp; co\" format=\"ascii\">3.5</DataArray>\n";
    write_text(path, vtu(piece(2, "0 0 0 1 1 1", data_a) + piece(1, "2 2 2", data_b) + piece(0, "", "")));
    ParticleData p = read_particles(path);
    REQUIRE(p.size() == 3);
    REQUIRE(p.positions == std::vector<float>{0, 0, 0, 1, 1, 1, 2, 2, 2});
    REQUIRE(p.attributes.size() == 2);  // the String array is skipped
    CHECK(p.attributes[0].name == "rho & co");
    CHECK(p.attributes[0].values == std::vector<float>{1.5f, 2.5f, 3.5f});
    CHECK(p.attributes[1].name == "flag");
    CHECK(p.attributes[1].components == 2);
    CHECK(p.attributes[1].values == std::vector<float>{-1, 2, 3, 4, 5, 6});

    // A later piece without one of the first piece's arrays.
    write_text(path, vtu(piece(1, "0 0 0", "<DataArray type=\"Float32\" Name=\"a\" format=\"ascii\">1</DataArray>") +
                         piece(1, "1 1 1", "")));
    require_error(path, "has no point array 'a'");
}

TEST_CASE("VTK XML: unsupported variants are named", "[formats]") {
    TempDir dir("vtu_unsupported");
    std::string path = dir.file("u.vtu");
    write_text(path, vtu(piece(1, "0 0 0", ""), " compressor=\"vtkLZ4DataCompressor\""));
    require_error(path, "compressor 'vtkLZ4DataCompressor'");
    write_text(path, "<VTKFile type=\"PUnstructuredGrid\" version=\"1.0\"><PUnstructuredGrid/></VTKFile>");
    require_error(path, "parallel PUnstructuredGrid");
    write_text(path, "<VTKFile type=\"ImageData\" version=\"1.0\"><ImageData/></VTKFile>");
    require_error(path, "unsupported VTK XML dataset type 'ImageData'");
    write_text(path, vtu(piece(1, "0 0 0", ""), " header_type=\"UInt16\""));
    require_error(path, "header_type 'UInt16'");
    write_text(path, vtu(piece(1, "0 0 0", "<DataArray type=\"Bit\" Name=\"b\" format=\"ascii\">1</DataArray>")));
    require_error(path, "unsupported type 'Bit'");
    write_text(path, "<?xml version=\"1.0\"?>\n<html><body/></html>");
    require_error(path, "not a VTK XML file");
}

TEST_CASE("VTK XML: wrong counts, offsets and sizes", "[formats]") {
    TempDir dir("vtu_bad");
    std::string path = dir.file("b.vtu");
    write_text(path, vtu(piece(3, "0 0 0 1 1 1           ", "")));
    require_error(path, "only 6 of 9 values");
    write_text(path, vtu(piece(3, "0 0 0 1 1 1", "")));
    require_error(path, "9 ASCII values cannot fit in its 11 characters");
    write_text(path, vtu(piece(1, "0 0 0 1 1 1", "")));
    require_error(path, "more than the 3 values");
    write_text(path, vtu(piece(1000000000, "0 0 0", "")));
    require_error(path, "cannot fit in its");
    write_text(path, vtu(piece(1, "0 0 zero", "")));
    require_error(path, "bad value 'zero'");

    // Appended raw data: a size header that disagrees with NumberOfPoints, an offset past the data, shared offsets.
    Bytes raw = read_bytes(kFormats + "/variants/raw_plain_uint32_le.vtu");
    std::string text = as_text(raw);
    std::string bad = text;
    bad.replace(bad.find("NumberOfPoints=\"5\""), 18, "NumberOfPoints=\"6\"");
    write_text(path, bad);
    require_error(path, "Points DataArray holds 60 bytes but 18 values of type Float32 need 72");
    bad = text;
    bad.replace(bad.find("offset=\"24\""), 11, "offset=\"9999999\"");
    write_text(path, bad);
    require_error(path, "beyond the");
    bad = text;
    bad.replace(bad.find("offset=\"24\""), 11, "offset=\"0\"  ");
    write_text(path, bad);
    require_error(path, "same appended offset 0");
    // Cut inside the appended data.
    write_bytes(path, Bytes(raw.begin(), raw.begin() + static_cast<std::ptrdiff_t>(text.find("_") + 30)));
    require_error(path, "");
}

TEST_CASE("VTK XML: corrupt zlib blocks and base64", "[formats]") {
    TempDir dir("vtu_zlib");
    std::string path = dir.file("z.vtu");
    std::string text = as_text(read_bytes(kFormats + "/dam26_zlib_base64.vtu"));
    // Flip a base64 character deep inside the compressed velocity data: zlib notices (or the size does).
    const std::size_t appended = text.find("   _") + 4;
    std::string bad = text;
    std::size_t at = appended + 20000;
    bad[at] = bad[at] == 'A' ? 'B' : 'A';
    write_text(path, bad);
    require_error(path, "DataArray");
    bad = text;
    bad[appended + 10] = '*';
    write_text(path, bad);
    require_error(path, "invalid base64 character '*'");
}

// ---------------------------------------------------------------------------------------------------------------
// PLY, NumPy, CSV, XYZ details

TEST_CASE("PLY: a mesh file gives its vertices, a file without vertices is refused", "[formats]") {
    ParticleData p = read_particles(std::string(MENISCUS_TEST_DATA) + "/io/quad_ascii.ply");
    REQUIRE(p.size() > 0);
    TempDir dir("ply");
    std::string path = dir.file("n.ply");
    write_text(path, "ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\nproperty float y\nproperty float z\n"
                     "property float nx\nproperty float ny\nproperty float nz\nproperty uchar red\nend_header\n"
                     "0 0 0 0 0 1 255\n1 1 1 0 1 0 7\n");
    p = read_particles(path);
    REQUIRE(p.size() == 2);
    REQUIRE(p.attributes.size() == 2);
    CHECK(p.attributes[0].name == "normal");
    CHECK(p.attributes[0].values == std::vector<float>{0, 0, 1, 0, 1, 0});
    CHECK(p.attributes[1].name == "red");
    write_text(path, "ply\nformat ascii 1.0\nelement face 0\nproperty list uchar int vertex_indices\nend_header\n");
    require_error(path, "no vertex element");
    write_text(path, "ply\nformat binary_little_endian 1.0\nelement vertex 1000\nproperty float x\nproperty float y\n"
                     "property float z\nend_header\n");
    require_error(path, "count 1000 needs at least 12000 bytes");
}

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
    require_error(path, "shape (2, 4); particle positions need shape (N, 3)");
    for (const char* object : {"|O", "|O8"}) {
        write_bytes(path, npy("{'descr': '" + std::string(object) + "', 'fortran_order': False, 'shape': (2, 3), }", Bytes(48)));
        require_error(path, "object arrays are pickles");
    }
    write_bytes(path, npy("{'descr': '<c8', 'fortran_order': False, 'shape': (2, 3), }", Bytes(48)));
    require_error(path, "unsupported dtype '<c8'");
    write_bytes(path, npy("{'descr': [('a', '<f4')], 'fortran_order': False, 'shape': (1,)}", Bytes(4)));
    require_error(path, "no fields x, y, z");
    write_bytes(path, npy("{'descr': '<f4', 'fortran_order': False, 'shape': (1000000, 3), }", Bytes(12)));
    require_error(path, "array data of shape (1000000, 3)");
    write_bytes(path, npy("{'descr': '<f4', 'fortran_order': False, 'shape': (-1, 3), }", Bytes(12)));
    require_error(path, "not a non-negative integer");
    write_bytes(path, npy("{'descr': '<f4', 'fortran_order': False, 'shape': (99999999999, 99999999999, 99999999999), }", Bytes(12)));
    require_error(path, "impossibly large");
    write_bytes(path, npy("{'descr': '<f4', 'shape': (1, 3)", Bytes(12)));
    require_error(path, "bad .npy header");
    Bytes v9 = npy("{'descr': '<f4', 'fortran_order': False, 'shape': (1, 3), }", Bytes(12));
    v9[6] = 9;
    write_bytes(path, v9);
    require_error(path, "format version 9.0");
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
    require_error(path, "compression method 12 (bzip2)");
    bad = zip;
    bad[entries[1] + 8] |= 1;
    write_bytes(path, bad);
    require_error(path, "encrypted");
    bad = zip;
    bad[entries[0] - 1000] ^= 0x40;  // a byte of the last member's data
    write_bytes(path, bad);
    require_error(path, "CRC-32 mismatch");
    write_bytes(path, Bytes(zip.begin(), zip.begin() + 70000));
    require_error(path, "end-of-central-directory");

    // Archives without positions, or with nothing but other files.
    write_bytes(path, zip_stored({{"time.npy", npy("{'descr': '<f8', 'fortran_order': False, 'shape': (), }", Bytes(8))},
                                  {"v.npy", npy("{'descr': '<f4', 'fortran_order': False, 'shape': (2, 2), }", Bytes(16))}}));
    require_error(path, "no particle positions in the .npz archive: expected an (N, 3) member");
    require_error(path, "time (), v (2, 2)");
    write_bytes(path, zip_stored({{"readme.txt", as_bytes("hello")}}));
    require_error(path, "no .npy members");
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
    require_error(path, "line 3 has 2 fields but the header has 3");
    write_text(path, "x,y,z\n1,2,3\n4,five,6\n");
    require_error(path, "line 3, column 'y': bad value 'five'");
    write_text(path, "x,y,z\n1,,3\n");
    require_error(path, "column 'y': empty value");
    write_text(path, "a,b,c\n1,2,3\n");
    require_error(path, "no columns x, y and z");
    write_text(path, "x,y,z\n");
    REQUIRE(read_particles(path).size() == 0);  // a header only: zero particles, like an empty frame
}

TEST_CASE("XYZ: raw size, byte order and text lines", "[formats]") {
    TempDir dir("xyz");
    std::string path = dir.file("a.xyz");
    Bytes raw = read_bytes(kFormats + "/dam26.xyz");
    write_bytes(path, Bytes(raw.begin(), raw.end() - 5));
    require_error(path, "not a multiple of 12");
    Bytes swapped = raw;
    for (std::size_t i = 0; i < swapped.size(); i += 4) {
        std::swap(swapped[i], swapped[i + 3]);
        std::swap(swapped[i + 1], swapped[i + 2]);
    }
    write_bytes(path, swapped);
    require_error(path, "byte-swapped");
    write_text(path, "1 2 3\n4 5 6 7\n");
    require_error(path, "line 2 has 4 values");
    write_text(path, "1,2,3\n# comment\n4;5;6\n");
    REQUIRE(read_particles(path).positions == std::vector<float>{1, 2, 3, 4, 5, 6});
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
    require_error(path, "has 5 numeric tuples for 6 points");
    bad = text;
    bad.replace(bad.find("\"pointcount\",5"), 14, "\"pointcount\",-1");
    write_text(path, bad);
    require_error(path, "without a valid \"pointcount\"");
    bad = text;
    bad.replace(bad.find("\"name\",\"P\""), 10, "\"name\",\"Q\"");
    write_text(path, bad);
    require_error(path, "has no numeric point attribute P");
    write_text(path, std::string(200, '[') + "\"pointcount\"");
    require_error(path, "nested more than 64 levels");

    path = dir.file("g.bgeo");
    Bytes binary = read_bytes(kFormats + "/variants/houdini_paged_le.bgeo");
    Bytes cut(binary.begin(), binary.end() - 40);
    write_bytes(path, cut);
    require_error(path, "truncated");
    Bytes magic = binary;
    magic[4] = 'x';
    write_bytes(path, magic);
    require_error(path, "unsupported BGEO variant: a binary JSON header");

    // Blosc-compressed .sc: by extension, and by its "scf1" header under any name.
    std::string sc = dir.file("fluid.0001.bgeo.sc");
    write_bytes(sc, Bytes{0x62, 0x6c, 0x6f, 0x73, 0x63, 1, 2, 3});
    require_error(sc, "Blosc");
    std::string scf = dir.file("fluid.0001.bgeo");
    write_bytes(scf, as_bytes("scf1" + std::string(40, '\0')));
    require_error(scf, "Blosc");
    std::string geo = dir.file("fluid.geo");
    write_text(geo, "PGEOMETRY V5\nNPoints 1 NPrims 0\n");
    require_error(geo, "unsupported BGEO variant: ASCII .geo");
}
