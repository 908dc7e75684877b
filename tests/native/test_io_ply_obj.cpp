// PLY and OBJ: particles from PLY vertices, mesh round trips, ASCII and big-endian PLY, OBJ face forms, writing
// errors and damaged meshes.
#include <catch2/catch.hpp>
#include <filesystem>
#include <random>
#include <string>
#include <vector>
#include "reader_checks.h"

using namespace meniscus;
using namespace meniscus::test;
namespace fs = std::filesystem;

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
    require_particle_error(path, "no vertex element");
    write_text(path, "ply\nformat binary_little_endian 1.0\nelement vertex 1000\nproperty float x\nproperty float y\n"
                     "property float z\nend_header\n");
    require_particle_error(path, "count 1000 needs at least 12000 bytes");
}

TEST_CASE("PLY round trip keeps vertices, triangles, normals and attributes", "[io]") {
    TempDir dir("ply");
    TriMesh mesh = make_test_mesh();
    std::string path = dir.file("mesh.ply");
    require_round_trip(mesh, path);

    std::string header(reinterpret_cast<const char*>(read_bytes(path).data()), 400);
    CHECK_THAT(header, Catch::Contains("format binary_little_endian 1.0"));
    CHECK_THAT(header, Catch::Contains("property float velocity_x\nproperty float velocity_y\nproperty float velocity_z\n"));
    CHECK_THAT(header, Catch::Contains("property float uv_0\nproperty float uv_1\n"));
    CHECK_THAT(header, Catch::Contains("property list uchar int vertex_indices"));

    // Without normals and attributes; and an empty mesh.
    TriMesh bare = mesh;
    bare.normals.clear();
    bare.attributes.clear();
    require_round_trip(bare, path);
    require_empty_round_trip(path);
}

TEST_CASE("OBJ round trip keeps vertices, triangles and normals", "[io]") {
    TempDir dir("obj");
    TriMesh mesh = make_test_mesh();
    std::string path = dir.file("mesh.obj");
    REQUIRE(require_round_trip(mesh, path, false).attributes.empty());

    TriMesh bare = mesh;
    bare.normals.clear();
    require_round_trip(bare, path, false);
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
