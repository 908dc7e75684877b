// Legacy VTK: particles from every section and type, ASCII and binary, 4.x and 5.x, damaged headers; and the
// VTK meshes write_mesh writes.
#include <catch2/catch.hpp>
#include <cstdio>
#include <cstring>
#include <random>
#include <string>
#include <vector>
#include "reader_checks.h"

using namespace meniscus;
using namespace meniscus::test;
namespace fs = std::filesystem;

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

// ---------------------------------------------------------------------------------------------------------------
// Meshes read back (read_mesh)

TEST_CASE("VTK meshes round-trip through write_mesh and read_mesh", "[io]") {
    TempDir dir("vtkmesh");
    const std::string path = dir.file("mesh.vtk");
    TriMesh mesh = make_test_mesh();  // attributes of 1 (SCALARS), 3 (VECTORS) and 2 (FIELD) components
    for (const auto& a : require_round_trip(mesh, path).attributes) CHECK(!a.integral);  // written as float

    // Without normals, without attributes, and empty.
    TriMesh bare = mesh;
    bare.normals.clear();
    require_round_trip(bare, path);
    bare.attributes.clear();
    require_round_trip(bare, path);
    require_empty_round_trip(path);

    // Names are made header-safe on writing; gzip and a name without the extension are recognised by content.
    TriMesh spaced = mesh;
    spaced.attributes[0].name = "rest density";
    write_mesh(spaced, path);
    REQUIRE(read_mesh(path).attributes[0].name == "rest_density");
    const std::string gz = dir.file("mesh.vtk.gz"), plain = dir.file("mesh.dat");
    write_bytes(gz, gzip(read_bytes(path)));
    write_bytes(plain, read_bytes(path));
    CHECK(read_mesh(gz).triangles == mesh.triangles);
    CHECK(read_mesh(plain).vertices == mesh.vertices);
}

TEST_CASE("ASCII VTK meshes, 4.x and 5.x polygons, fanned into triangles", "[io]") {
    TempDir dir("vtkmesh_ascii");
    const std::string path = dir.file("quad.vtk");
    const std::string points = "POINTS 5 float\n0 0 0  1 0 0  1 1 0  0 1 0  0 0 1\n";
    const std::string point_data = "POINT_DATA 5\nNORMALS n float\n0 0 1 0 0 1 0 0 1 0 0 1 1 0 0\n"
                                   "SCALARS id int 1\nLOOKUP_TABLE default\n7 8 9 10 11\n"
                                   "FIELD FieldData 1\nuv 2 5 float\n0 0 1 0 1 1 0 1 0.5 0.5\n";
    for (const std::string polygons : {std::string("POLYGONS 2 9\n4 0 1 2 3\n3 0 1 4\n"),
                                       std::string("POLYGONS 3 7\nOFFSETS vtktypeint64\n0 4 7\nCONNECTIVITY vtktypeint64\n0 1 2 3 0 1 4\n")}) {
        INFO(polygons);
        write_text(path, "# vtk DataFile Version 5.1\nquad and triangle\nASCII\nDATASET POLYDATA\n" + points +
                             "VERTICES 2 1\nOFFSETS vtktypeint64\n0 1\nCONNECTIVITY vtktypeint64\n4\n" + polygons + point_data);
        TriMesh m = read_mesh(path);
        REQUIRE(m.num_vertices() == 5);
        REQUIRE(m.triangles == std::vector<int32_t>{0, 1, 2, 0, 2, 3, 0, 1, 4});
        REQUIRE(m.normals.size() == 15);
        CHECK(m.normals[12] == 1.0f);
        REQUIRE(m.attributes.size() == 2);
        CHECK(m.attributes[0].name == "id");
        CHECK(m.attributes[0].integral);
        CHECK(m.attributes[0].values == std::vector<float>{7, 8, 9, 10, 11});
        CHECK(m.attributes[1].name == "uv");
        CHECK(m.attributes[1].components == 2);
        CHECK(m.attributes[1].values[8] == 0.5f);
    }
}

TEST_CASE("damaged and unsupported VTK meshes give FormatError naming the file and the problem", "[io]") {
    TempDir dir("vtkmesh_bad");
    const std::string path = dir.file("bad.vtk");
    const std::string head = "# vtk DataFile Version 4.2\nbad\nASCII\nDATASET POLYDATA\nPOINTS 3 float\n0 0 0 1 0 0 0 1 0\n";
    struct Case {
        std::string text, expect;
    };
    const Case cases[] = {
        {head + "POLYGONS 1 4\n3 0 1 3\n", "POLYGONS cell 0 refers to vertex 3 but there are only 3 points"},
        {head + "POLYGONS 1 4\n3 0 1 -1\n", "refers to vertex -1"},
        {head + "POLYGONS 1 3\n2 0 1\n", "POLYGONS cell 0 has only 2 vertices"},
        {head + "POLYGONS 1 4\n5 0 1 2\n", "POLYGONS cell 0 runs past the 4 values"},
        {head + "POLYGONS 1 5\n3 0 1 2 7\n", "POLYGONS has 1 cells in 4 values, but its size says 5"},
        {head + "POLYGONS 1 4\n3 0 1 2.5\n", "bad value '2.5' in POLYGONS data"},
        {head + "POLYGONS 1 4\n3 0 1 2\nPOLYGONS 1 4\n3 0 1 2\n", "second POLYGONS section"},
        {head + "TRIANGLE_STRIPS 1 4\n3 0 1 2\n", "TRIANGLE_STRIPS"},
        {head + "POLYGONS 2 3\nOFFSETS float\n0 3\nCONNECTIVITY vtktypeint64\n0 1 2\n", "cell indices must be integers"},
        {head + "POLYGONS 2 3\nOFFSETS vtktypeint64\n0 4\nCONNECTIVITY vtktypeint64\n0 1 2\n", "POLYGONS OFFSETS value 1 (4)"},
        {head + "POLYGONS 2 3\nOFFSETS vtktypeint64\n1 3\nCONNECTIVITY vtktypeint64\n0 1 2\n", "POLYGONS OFFSETS value 0 (1)"},
        {head + "POLYGONS 2 3\nOFFSETS vtktypeint64\n0 2\nCONNECTIVITY vtktypeint64\n0 1 2\n", "OFFSETS end at 2 but CONNECTIVITY has 3"},
        {"# vtk DataFile Version 4.2\nbad\nASCII\nDATASET UNSTRUCTURED_GRID\nPOINTS 3 float\n0 0 0 1 0 0 0 1 0\n"
         "CELLS 1 4\n3 0 1 2\nCELL_TYPES 1\n5\n", "must be DATASET POLYDATA"},
        {"# vtk DataFile Version 4.2\nbad\nASCII\nDATASET POLYDATA\n", "no POINTS section"},
        {head, "no POLYGONS section"},
    };
    for (const auto& c : cases) {
        INFO(c.text);
        write_text(path, c.text);
        require_mesh_error(path, c.expect);
    }
    // Every cut of a binary mesh: a FormatError naming the file, or (at a section boundary after the polygons) the
    // whole geometry with the point data before the cut; cuts up to the end of the polygons always fail.
    TriMesh mesh = make_test_mesh();
    write_mesh(mesh, path);
    const Bytes bytes = read_bytes(path);
    const std::string text = as_text(bytes);
    const std::size_t polygons_end = text.find("\nPOINT_DATA");
    REQUIRE(polygons_end != std::string::npos);
    const std::string cut = dir.file("cut.vtk");
    for (std::size_t length = 1; length < bytes.size(); ++length) {
        write_bytes(cut, bytes, length);
        const std::string message = format_error_of([&] {
            TriMesh m = read_mesh(cut);
            REQUIRE(m.vertices == mesh.vertices);
            REQUIRE(m.triangles == mesh.triangles);
            for (const auto& a : m.attributes) REQUIRE(a.values.size() == m.num_vertices() * static_cast<std::size_t>(a.components));
        });
        INFO("cut at " << length << ": " << message);
        if (length < polygons_end) REQUIRE(!message.empty());
        if (!message.empty()) REQUIRE(starts_with(message, cut));
    }
    // Unknown formats name what is supported.
    const std::string stl = dir.file("mesh.stl");
    write_text(stl, "solid x\n");
    require_mesh_error(stl, "(supported: .ply, .obj, .vtk)");
}
