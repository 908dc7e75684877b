// Mantaflow's cache (Blender's fluid simulation): UNI particles placed in the world by the cache's config, their
// velocities in m/s, bobj meshes, and the refusals. The files are written here with a known domain placement
// (rotated, scaled, moved), so every expected coordinate is worked out by hand; tests/python/test_mantaflow.py reads
// real bakes.
#include <catch2/catch.hpp>
#include <cstdint>
#include <cstring>
#include <string>
#include <vector>

#include "io/formats/mantaflow.h"
#include "reader_checks.h"

using namespace meniscus;
using namespace meniscus::test;

namespace {

void put_i32(Bytes& b, std::int32_t v) {
    for (int k = 0; k < 4; ++k) b.push_back(static_cast<unsigned char>(static_cast<std::uint32_t>(v) >> (8 * k)));
}
void put_f32(Bytes& b, float f) {
    std::uint32_t u;
    std::memcpy(&u, &f, 4);
    put_i32(b, static_cast<std::int32_t>(u));
}

Bytes uni_header(const char* magic, std::int32_t count, std::int32_t element_bytes, std::array<int, 3> grid = {16, 16, 8}) {
    Bytes b(magic, magic + 4);
    put_i32(b, count);
    for (int g : grid) put_i32(b, g);
    put_i32(b, element_bytes == 16 ? 0 : 1);
    put_i32(b, element_bytes);
    b.resize(b.size() + 256 + 8, 0);
    return b;
}

struct Particle {
    float x, y, z;
    std::int32_t flag;
};

Bytes particle_system(const std::vector<Particle>& particles, std::array<int, 3> grid = {16, 16, 8}) {
    Bytes b = uni_header("PB02", static_cast<std::int32_t>(particles.size()), 16, grid);
    for (const auto& p : particles) {
        put_f32(b, p.x);
        put_f32(b, p.y);
        put_f32(b, p.z);
        put_i32(b, p.flag);
    }
    return b;
}

Bytes vec3_data(const std::vector<std::array<float, 3>>& values) {
    Bytes b = uni_header("PD01", static_cast<std::int32_t>(values.size()), 12);
    for (const auto& v : values)
        for (float f : v) put_f32(b, f);
    return b;
}

// A 2 x 2 x 2 domain mesh (p0 -1, p1 1) with scale (1, 1, +-0.5), turned 90 degrees about z and moved to (3, 4, 5):
// world size 2 x 2 x 1, resolution 16 -> a 16 x 16 x 8 grid of 0.125 m cells.
Bytes config(float z_scale = 0.5f, std::array<int, 3> resolution = {16, 16, 8}) {
    Bytes b;
    put_i32(b, 16);
    for (int r : resolution) put_i32(b, r);
    put_f32(b, 1.0f / 16);  // dx
    put_f32(b, 0.104f);     // dt
    for (float v : {-1.0f, -1.0f, -1.0f, 1.0f, 1.0f, 1.0f, -1.0f, -1.0f, -1.0f}) put_f32(b, v);  // p0, p1, dp0
    for (int k = 0; k < 3; ++k) put_i32(b, 0);                                                  // shift
    for (int k = 0; k < 3; ++k) put_f32(b, 0.0f);                                               // object shift
    for (float v : {0.0f, 1.0f, 0.0f, 0.0f, -1.0f, 0.0f, 0.0f, 0.0f, 0.0f, 0.0f, z_scale, 0.0f, 3.0f, 4.0f, 5.0f, 1.0f})
        put_f32(b, v);  // column-major object matrix
    for (int r : {16, 16, 8}) put_i32(b, r);  // base resolution
    for (int k = 0; k < 3; ++k) put_i32(b, 0);
    for (int r : {16, 16, 8}) put_i32(b, r);
    for (int k = 0; k < 3; ++k) put_f32(b, 0.0f);  // active colour
    put_f32(b, 1.0f);                              // time total
    b.insert(b.end(), {'C', '0', '1', 0});
    return b;
}

// <dir>/cache/{data,config,mesh}: Blender's layout.
struct Cache {
    TempDir dir{"mantaflow"};
    std::string data, config_dir, mesh;
    Cache() {
        data = (dir.path / "cache" / "data").string();
        config_dir = (dir.path / "cache" / "config").string();
        mesh = (dir.path / "cache" / "mesh").string();
        for (const auto& d : {data, config_dir, mesh}) fs::create_directories(d);
    }
    std::string write(const std::string& folder, const std::string& name, const Bytes& bytes, bool compress = true) {
        const std::string path = folder + "/" + name;
        write_bytes(path, compress ? gzip(bytes) : bytes);
        return path;
    }
};

void require_near(const float* p, std::array<double, 3> expect) {
    for (int k = 0; k < 3; ++k) REQUIRE(p[k] == Approx(expect[k]).margin(1e-5));
}

}  // namespace

TEST_CASE("Mantaflow UNI particles are placed in the world by the cache's config, with velocities in m/s", "[io][mantaflow]") {
    Cache cache;
    cache.write(cache.config_dir, "config_0007.uni", config());
    // Grid corner 0, the far corner, an inner point, and one particle Mantaflow marked deleted (dropped).
    const std::string pp = cache.write(cache.data, "pp_0007.uni",
                                       particle_system({{0, 0, 0, 0}, {16, 16, 8, 1}, {8, 4, 6, 0}, {1, 1, 1, 1 << 10}}));
    ParticleData p = read_particles(pp);
    REQUIRE(p.size() == 3);
    require_near(&p.positions[0], {4.0, 3.0, 4.5});
    require_near(&p.positions[3], {2.0, 5.0, 5.5});
    require_near(&p.positions[6], {3.5, 4.0, 5.25});
    CHECK(p.attributes.empty());  // no pVel file: no velocity

    REQUIRE(p.fluid_domain.has_value());
    const FluidDomain& d = *p.fluid_domain;
    CHECK(d.resolution == std::array<int, 3>{16, 16, 8});
    for (int k = 0; k < 3; ++k) CHECK(d.origin[k] == Approx(std::array<double, 3>{4.0, 3.0, 4.5}[k]));
    CHECK(d.axes[0][1] == Approx(0.125));  // grid x runs along world y (turned 90 degrees)
    CHECK(d.axes[1][0] == Approx(-0.125));
    CHECK(d.axes[2][2] == Approx(0.125));

    // Cells per Mantaflow time unit -> m/s: * 0.125 m * 2.5 time units per second, turned like the grid.
    cache.write(cache.data, "pVel_0007.uni", vec3_data({{1, 0, 0}, {0, 2, 0}, {0, 0, -4}, {9, 9, 9}}));
    p = read_particles(pp);
    REQUIRE(p.attributes.size() == 1);
    CHECK(p.attributes[0].name == "velocity");
    REQUIRE(p.attributes[0].components == 3);
    require_near(&p.attributes[0].values[0], {0.0, 0.3125, 0.0});
    require_near(&p.attributes[0].values[3], {-0.625, 0.0, 0.0});
    require_near(&p.attributes[0].values[6], {0.0, 0.0, -1.25});

    // Uncompressed files read the same.
    cache.write(cache.data, "pp_0007.uni", particle_system({{8, 4, 6, 0}}), false);
    cache.write(cache.data, "pVel_0007.uni", vec3_data({{1, 0, 0}}), false);
    p = read_particles(pp);
    REQUIRE(p.size() == 1);
    require_near(&p.positions[0], {3.5, 4.0, 5.25});
}

TEST_CASE("Mantaflow bobj meshes are placed as Blender shows them", "[io][mantaflow]") {
    Cache cache;
    cache.write(cache.config_dir, "config_0012.uni", config());
    Bytes bobj;
    put_i32(bobj, 3);  // vertices, normalised: (grid - resolution / 2) / 16
    for (float v : {0.0f, 0.0f, 0.0f, 0.5f, 0.0f, 0.0f, 0.0f, 0.25f, -0.25f}) put_f32(bobj, v);
    put_i32(bobj, 3);
    for (int k = 0; k < 9; ++k) put_f32(bobj, k == 2 || k == 5 || k == 8 ? 1.0f : 0.0f);
    put_i32(bobj, 1);
    for (int i : {0, 1, 2}) put_i32(bobj, i);
    const std::string path = cache.write(cache.mesh, "fluid_mesh_0012.bobj.gz", bobj);
    TriMesh m = read_mesh(path);
    REQUIRE(m.num_vertices() == 3);
    require_near(&m.vertices[0], {3.0, 4.0, 5.0});   // the domain's centre
    require_near(&m.vertices[3], {3.0, 5.0, 5.0});   // half the longest side along grid x = world y
    require_near(&m.vertices[6], {2.5, 4.0, 4.5});   // grid y = world -x; grid z: cells are cubes in the world
    CHECK(m.triangles == std::vector<int32_t>{0, 1, 2});

    // A mirrored domain keeps the triangles facing out.
    cache.write(cache.config_dir, "config_0012.uni", config(-0.5f));
    m = read_mesh(path);
    CHECK(m.triangles == std::vector<int32_t>{0, 2, 1});
    require_near(&m.vertices[6], {2.5, 4.0, 5.5});

    Bytes bad = bobj;
    bad[bad.size() - 4] = 3;  // a triangle's corner 3 of 3 vertices
    cache.write(cache.mesh, "fluid_mesh_0012.bobj.gz", bad);
    CHECK(require_mesh_error(path, "uses vertex 3 of 3").find("byte 92 of the decompressed data") != std::string::npos);
}

TEST_CASE("Mantaflow files that cannot be placed or read are refused with the file and the reason", "[io][mantaflow]") {
    Cache cache;
    const std::string pp = cache.write(cache.data, "pp_0003.uni", particle_system({{1, 2, 3, 0}, {4, 5, 6, 0}}));
    std::string e = require_particle_error(pp, "config_0003.uni, which does not exist");
    CHECK(starts_with(e, pp));

    const Bytes whole = config();
    cache.write(cache.config_dir, "config_0003.uni", Bytes(whole.begin(), whole.begin() + 150));
    // The reader joins the config's path with the platform's separator ('\\' on Windows).
    const std::string config_path = (fs::path(cache.config_dir) / "config_0003.uni").string();
    require_particle_error(pp, "its cache config cannot be read: " + config_path + ": a Mantaflow cache config holds 204 bytes, this one 150");
    Bytes flat = config(0.0f);
    cache.write(cache.config_dir, "config_0003.uni", flat);
    require_particle_error(pp, "zero scale on axis 2");
    Bytes far = config();  // the fuzzer's finding: res_min near INT_MIN overflowed res_max - res_min
    for (int k = 0; k < 4; ++k) far[160 + k] = static_cast<unsigned char>(static_cast<std::uint32_t>(-2147483587) >> (8 * k));
    cache.write(cache.config_dir, "config_0003.uni", far);
    require_particle_error(pp, "is not a domain's grid");
    cache.write(cache.config_dir, "config_0003.uni", config(0.5f, {16, 16, 9}));
    require_particle_error(pp, "grid but the cache's config of that frame says 16 x 16 x 9");
    cache.write(cache.config_dir, "config_0003.uni", config());
    CHECK(read_particles(pp).size() == 2);

    cache.write(cache.data, "pVel_0003.uni", vec3_data({{1, 0, 0}}));
    require_particle_error(cache.data + "/pVel_0003.uni", "holds no positions: read the frame's particle file pp_####.uni");
    const std::string velocity_path = (fs::path(cache.data) / "pVel_0003.uni").string();
    require_particle_error(pp, "its velocities cannot be read: " + velocity_path + ": holds 1 values on a 16 x 16 x 8 grid, but its particle file has 2");

    Bytes system = particle_system({{1, 2, 3, 0}, {4, 5, 6, 0}});
    cache.write(cache.data, "pVel_0003.uni", vec3_data({{1, 0, 0}, {0, 1, 0}}));
    cache.write(cache.data, "pp_0003.uni", Bytes(system.begin(), system.end() - 5));
    require_particle_error(pp, "truncated at byte 319 of the decompressed data");
    Bytes extra = system;
    extra.push_back(0);
    cache.write(cache.data, "pp_0003.uni", extra);
    require_particle_error(pp, "1 bytes after the last of 2 particles");
    Bytes nan = system;
    nan[292 + 16 + 7] = 0x7f, nan[292 + 16 + 6] = 0xc0;
    cache.write(cache.data, "pp_0003.uni", nan);
    require_particle_error(pp, "particle 1 has a non-finite position at byte 308");
    Bytes old = system;
    old[3] = '1';
    cache.write(cache.data, "pp_0003.uni", old);
    require_particle_error(pp, "version PB01");
    Bytes grid = system;
    grid[8] = 0;
    cache.write(cache.data, "pp_0003.uni", grid);
    require_particle_error(pp, "grid size 0 x 16 x 8 at byte 8");

    const std::string unnumbered = cache.write(cache.data, "particles.uni", system);
    require_particle_error(unnumbered, "has no frame number");
    Bytes vel_grid = as_bytes("MNT3");
    vel_grid.resize(400, 0);
    require_particle_error(cache.write(cache.data, "vel_0003.uni", vel_grid), "a Mantaflow grid");
}
