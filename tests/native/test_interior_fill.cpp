// The narrow-band fill (sph/interior_fill.h): what a shell of particles encloses is classified liquid or air, on
// hand-made shells shaped like Mantaflow's narrow band (2 x 2 x 2 jittered particles per cell, 3 cells deep).
#include <catch2/catch.hpp>

#include <array>
#include <cmath>
#include <cstdint>
#include <functional>
#include <initializer_list>
#include <limits>
#include <vector>

#include "band_particles.h"
#include "base/errors.h"
#include "pipeline.h"
#include "sph/interior_fill.h"

using namespace meniscus;

namespace {

constexpr double kCell = 0.1;

FluidDomain closed_domain(int n) {
    FluidDomain d;
    d.axes = {{{kCell, 0, 0}, {0, kCell, 0}, {0, 0, kCell}}};
    d.resolution = {n, n, n};
    d.band_width_cells = 3.0;
    return d;
}

// 2 x 2 x 2 jittered particles in every cell whose centre (in cells) passes `keep`.
std::vector<float> particles_where(int n, const std::function<bool(double, double, double)>& keep) {
    return test::band_particles(n, kCell, 12345u, keep);
}

PositionsView view(const std::vector<float>& p) { return PositionsView(p.data(), p.size() / 3); }

CellClass at(const InteriorClassification& c, int i, int j, int k) {
    return c.cells[i + c.resolution[0] * (j + c.resolution[1] * static_cast<std::size_t>(k))];
}

double sphere_distance(double x, double y, double z, double cx, double cy, double cz) {
    return std::sqrt((x - cx) * (x - cx) + (y - cy) * (y - cy) + (z - cz) * (z - cz));
}

// A pool 11 cells deep on the floor of a closed 24^3 domain: particles only in its top 3 cells (the band).
bool pool_band(double, double, double z) { return z > 9 && z < 12; }

double mesh_volume(const TriMesh& m) {
    double v = 0.0;
    for (std::size_t t = 0; t < m.triangles.size(); t += 3) {
        const float* a = &m.vertices[3 * m.triangles[t]];
        const float* b = &m.vertices[3 * m.triangles[t + 1]];
        const float* c = &m.vertices[3 * m.triangles[t + 2]];
        v += (double(a[0]) * (double(b[1]) * c[2] - double(b[2]) * c[1]) - double(a[1]) * (double(b[0]) * c[2] - double(b[2]) * c[0]) +
              double(a[2]) * (double(b[0]) * c[1] - double(b[1]) * c[0])) / 6.0;
    }
    return v;
}

}  // namespace

TEST_CASE("a hollow pool's band over a closed floor is filled down to the floor, the air above is not", "[interior_fill]") {
    const FluidDomain domain = closed_domain(24);
    const std::vector<float> particles = particles_where(24, pool_band);
    const InteriorClassification c = classify_interior(view(particles), domain, 2);
    for (int k = 1; k <= 7; ++k) CHECK(at(c, 12, 12, k) == CellClass::liquid);
    CHECK(at(c, 2, 20, 3) == CellClass::liquid);  // beside the side walls too
    for (int k = 14; k <= 22; ++k) CHECK(at(c, 12, 12, k) == CellClass::air);
    CHECK(at(c, 0, 12, 5) == CellClass::solid);  // the closed border's layer
    CHECK(c.count(CellClass::liquid) >= std::size_t(22 * 22 * 7));
    CHECK(c.split_components == 0);

    const InteriorFill fill = fill_interior(view(particles), domain, 0.5 * kCell, 2, 0);
    REQUIRE(fill.source.size() == fill.positions.size() / 3);
    REQUIRE(!fill.source.empty());
    float lowest = 1e9f, highest = -1e9f;
    for (std::size_t p = 2; p < fill.positions.size(); p += 3) {
        lowest = std::min(lowest, fill.positions[p]);
        highest = std::max(highest, fill.positions[p]);
    }
    CHECK(lowest < 1.5 * kCell);   // down to the floor's wall layer (cell 1 holds points at 1.25 cells)
    CHECK(highest < 10.0 * kCell); // not above the band's inner half
    for (uint32_t s : fill.source) CHECK(s < particles.size() / 3);
}

TEST_CASE("a hollow droplet is filled, the air around it is not", "[interior_fill]") {
    const FluidDomain domain = closed_domain(24);
    // A ball of radius 8 cells in mid-air with particles only in its outer 3 cells.
    const std::vector<float> particles = particles_where(24, [](double x, double y, double z) {
        const double r = sphere_distance(x, y, z, 12, 12, 13);
        return r > 5 && r < 8;
    });
    const InteriorClassification c = classify_interior(view(particles), domain, 2);
    CHECK(at(c, 12, 12, 13) == CellClass::liquid);
    CHECK(c.enclosed_components == 1);
    CHECK(at(c, 12, 12, 2) == CellClass::air);  // below it, above the floor: not a pillar of water
    CHECK(at(c, 12, 12, 22) == CellClass::air);
    CHECK(at(c, 2, 2, 2) == CellClass::air);
}

TEST_CASE("a bubble in a pool stays air, the water around it is filled", "[interior_fill]") {
    const FluidDomain domain = closed_domain(32);
    // A pool 29 cells deep (band in its top 3 cells) with a bubble of radius 4 cells, its band outside it: deep in
    // the water, or just under the surface, its band merging with the surface's.
    const double depth = GENERATE(12.0, 20.0);
    const std::vector<float> particles = particles_where(32, [&](double x, double y, double z) {
        const double r = sphere_distance(x, y, z, 16, 16, depth);
        return (z > 27 && z < 30) || (r > 4 && r < 7);
    });
    const InteriorClassification c = classify_interior(view(particles), domain, 2);
    CHECK(at(c, 16, 16, int(depth)) == CellClass::air);
    CHECK(at(c, 3, 3, 10) == CellClass::liquid);
    CHECK(at(c, 16, 16, 1) == CellClass::liquid);
    CHECK(at(c, 16, 16, 30) != CellClass::liquid);
    CHECK(c.enclosed_components == 1);
}

TEST_CASE("a thin jet over a dry floor is not filled underneath", "[interior_fill]") {
    const FluidDomain domain = closed_domain(24);
    const std::vector<float> particles = particles_where(24, [](double x, double y, double z) {
        return x > 4 && x < 20 && y > 10 && y < 13 && z > 12 && z < 14;
    });
    const InteriorClassification c = classify_interior(view(particles), domain, 2);
    CHECK(c.count(CellClass::liquid) == 0);
    CHECK(fill_interior(view(particles), domain, 0.5 * kCell, 2, 0).source.empty());
}

TEST_CASE("a wide thin sheet a few cells over a dry floor raises no pillar of water under it", "[interior_fill]") {
    const FluidDomain domain = closed_domain(24);
    // A sheet two cells thick (all band: thinner than two bands), 2 cells of air between its shell and the floor's
    // wall layer, far wider than high: in the middle, against one wall, in a corner, from wall to wall, against
    // three walls.
    struct Sheet { double x0, x1, y0, y1; };
    const Sheet sheet = GENERATE(Sheet{3, 21, 3, 21}, Sheet{1, 16, 4, 20}, Sheet{1, 14, 1, 14}, Sheet{1, 23, 8, 16},
                                 Sheet{1, 23, 1, 14});
    const double bottom = GENERATE(4.0, 5.0);
    CAPTURE(sheet.x0, sheet.x1, sheet.y0, sheet.y1, bottom);
    const std::vector<float> particles = particles_where(24, [&](double x, double y, double z) {
        return x > sheet.x0 && x < sheet.x1 && y > sheet.y0 && y < sheet.y1 && z > bottom && z < bottom + 2;
    });
    const InteriorClassification c = classify_interior(view(particles), domain, 2);
    const int i = int((sheet.x0 + sheet.x1) / 2), j = int((sheet.y0 + sheet.y1) / 2);
    for (int k = 1; k < int(bottom) - 1; ++k) CHECK(at(c, i, j, k) == CellClass::air);
    CHECK(c.count(CellClass::liquid) == 0);
    CHECK(fill_interior(view(particles), domain, 0.5 * kCell, 2, 0).source.empty());
}

TEST_CASE("a pool beside a step along a wall that nobody described is still filled", "[interior_fill]") {
    const FluidDomain domain = closed_domain(24);
    // A step from wall to wall in x, 5 cells deep in y, up to cell 16: no particles in it; the pool's band elsewhere.
    const auto in_step = [](double, double y, double z) { return y < 6 && z < 16; };
    const std::vector<float> particles = particles_where(24, [&](double x, double y, double z) { return pool_band(x, y, z) && !in_step(x, y, z); });
    const InteriorClassification c = classify_interior(view(particles), domain, 2);
    for (int k = 1; k <= 7; ++k) CHECK(at(c, 12, 14, k) == CellClass::liquid);
    CHECK(at(c, 3, 20, 2) == CellClass::liquid);
    CHECK(at(c, 12, 3, 4) == CellClass::air);  // the step's cells
    CHECK(c.count(CellClass::liquid) >= std::size_t(22 * 16 * 7));
}

TEST_CASE("an obstacle sticking out of a pool: solid when described, and the pool is filled either way", "[interior_fill]") {
    FluidDomain domain = closed_domain(24);
    // Pool band as above; a box obstacle from cell 6 to 12 in x and y, floor to cell 16 in z: no particles in it.
    const auto in_box = [](double x, double y, double z) { return x > 6 && x < 12 && y > 6 && y < 12 && z < 16; };
    const std::vector<float> particles = particles_where(24, [&](double x, double y, double z) { return pool_band(x, y, z) && !in_box(x, y, z); });

    SECTION("not described: the air above and the water below meet through the box's cells") {
        const InteriorClassification c = classify_interior(view(particles), domain, 2);
        CHECK(at(c, 18, 18, 4) == CellClass::liquid);
        CHECK(at(c, 3, 18, 6) == CellClass::liquid);
        CHECK(at(c, 9, 9, 14) == CellClass::air);  // the box above the water
        CHECK(at(c, 18, 18, 18) == CellClass::air);
    }
    SECTION("described as triangles: its cells are solid") {
        const float lo[3] = {float(6 * kCell), float(6 * kCell), 0.0f}, hi[3] = {float(12 * kCell), float(12 * kCell), float(16 * kCell)};
        std::vector<float> soup;
        // The box's 12 triangles (winding does not matter to the parity test).
        const int faces[6][4] = {{0, 1, 3, 2}, {4, 6, 7, 5}, {0, 4, 5, 1}, {2, 3, 7, 6}, {0, 2, 6, 4}, {1, 5, 7, 3}};
        const auto corner = [&](int v, int a) { return (v >> a) & 1 ? hi[a] : lo[a]; };
        for (const auto& f : faces)
            for (int t : {0, 1}) {
                const int tri[3] = {f[0], f[1 + t], f[2 + t]};
                for (int v : tri) soup.insert(soup.end(), {corner(v, 0), corner(v, 1), corner(v, 2)});
            }
        domain.obstacles.push_back(soup);
        const InteriorClassification c = classify_interior(view(particles), domain, 2);
        CHECK(at(c, 9, 9, 4) == CellClass::solid);
        CHECK(at(c, 9, 9, 14) == CellClass::solid);
        CHECK(at(c, 9, 9, 18) == CellClass::air);
        CHECK(at(c, 18, 18, 4) == CellClass::liquid);
        CHECK(c.split_components == 0);
    }
}

// The 2 triangles of each listed face of the box from lo to hi (cells), world space: faces 0..5 are -z, +z, -y, +y,
// -x, +x.
std::vector<float> box_faces(const std::array<double, 3>& lo, const std::array<double, 3>& hi, std::initializer_list<int> which) {
    const int faces[6][4] = {{0, 1, 3, 2}, {4, 6, 7, 5}, {0, 4, 5, 1}, {2, 3, 7, 6}, {0, 2, 6, 4}, {1, 5, 7, 3}};
    const auto corner = [&](int v, int a) { return float(((v >> a) & 1 ? hi[a] : lo[a]) * kCell); };
    std::vector<float> soup;
    for (int f : which)
        for (int t : {0, 1}) {
            const int tri[3] = {faces[f][0], faces[f][1 + t], faces[f][2 + t]};
            for (int v : tri) soup.insert(soup.end(), {corner(v, 0), corner(v, 1), corner(v, 2)});
        }
    return soup;
}

TEST_CASE("a single-sided plane obstacle gives solid cells where it lies", "[interior_fill]") {
    FluidDomain domain = closed_domain(24);
    domain.obstacles.push_back(box_faces({4.5, 4.5, 6.4}, {19.5, 19.5, 6.4}, {0}));  // a horizontal square over 16 x 16 cells
    const std::vector<float> particles = particles_where(24, pool_band);
    const InteriorClassification c = classify_interior(view(particles), domain, 2);
    for (int i = 4; i < 20; ++i) CHECK(at(c, i, 12, 6) == CellClass::solid);
    CHECK(at(c, 12, 12, 5) != CellClass::solid);
    CHECK(at(c, 12, 12, 7) == CellClass::liquid);
    CHECK(at(c, 2, 12, 6) == CellClass::liquid);  // beside it, the pool
    CHECK(c.count(CellClass::solid) == std::size_t(24 * 24 * 24 - 22 * 22 * 22 + 16 * 16));
}

TEST_CASE("water in an open box obstacle is held by its walls and filled, the dry floor around it is not", "[interior_fill]") {
    FluidDomain domain = closed_domain(24);
    // A box without a lid from the floor's wall layer up to cell 14; water up to cell 12 in it, its band in the top 3
    // cells; nothing outside it. Its walls, single planes, would otherwise let the water's cells see the dry floor.
    domain.obstacles.push_back(box_faces({6.2, 6.2, 1.2}, {17.8, 17.8, 14}, {0, 2, 3, 4, 5}));
    const std::vector<float> particles = particles_where(24, [](double x, double y, double z) {
        return x > 7 && x < 17 && y > 7 && y < 17 && pool_band(x, y, z);
    });
    const InteriorClassification c = classify_interior(view(particles), domain, 2);
    for (int k = 2; k <= 7; ++k) CHECK(at(c, 12, 12, k) == CellClass::liquid);
    CHECK(at(c, 6, 12, 4) == CellClass::solid);
    CHECK(at(c, 17, 12, 4) == CellClass::solid);
    CHECK(at(c, 12, 12, 1) == CellClass::solid);
    CHECK(at(c, 3, 3, 4) == CellClass::air);
    CHECK(at(c, 20, 12, 2) == CellClass::air);
    CHECK(at(c, 12, 12, 16) == CellClass::air);
    CHECK(c.count(CellClass::liquid) >= std::size_t(10 * 10 * 6));
}

TEST_CASE("a pool whose band holds no particles in some of its cells is still filled", "[interior_fill]") {
    // A sparse Particle Sampling leaves cells of the band empty: here the band's middle layer in two columns of three.
    // The band still spans its 3 cells over the water, so the water under it is no sheet over air.
    const FluidDomain domain = closed_domain(24);
    const std::vector<float> particles = particles_where(24, [](double x, double y, double z) {
        const bool sparse_column = (int(x) + int(y)) % 3 != 0;
        return pool_band(x, y, z) && !(sparse_column && z > 10 && z < 11);
    });
    const InteriorClassification c = classify_interior(view(particles), domain, 2);
    for (int k = 1; k <= 7; ++k) CHECK(at(c, 12, 12, k) == CellClass::liquid);
    CHECK(c.count(CellClass::liquid) >= std::size_t(22 * 22 * 7));
}

TEST_CASE("a pool under a wide floating obstacle is filled under it and around it", "[interior_fill]") {
    // A raft (a closed slab from cell 3 to 21 in x and y, 8 to 14 in z) floating in the pool: the band's particles
    // lie around it, none in it or under it. The column votes under the raft see through it to the air above; the
    // water there must still count as held (by the raft above), not as water open to air on its sides.
    FluidDomain domain = closed_domain(24);
    domain.obstacles.push_back(box_faces({3, 3, 8}, {21, 21, 14}, {0, 1, 2, 3, 4, 5}));
    const auto in_raft = [](double x, double y, double z) { return x > 3 && x < 21 && y > 3 && y < 21 && z > 8 && z < 14; };
    const std::vector<float> particles = particles_where(24, [&](double x, double y, double z) {
        return pool_band(x, y, z) && !in_raft(x, y, z);
    });
    const InteriorClassification c = classify_interior(view(particles), domain, 2);
    CHECK(at(c, 12, 12, 10) == CellClass::solid);
    for (int k = 1; k <= 6; ++k) CHECK(at(c, 12, 12, k) == CellClass::liquid);  // under the raft
    for (int k = 1; k <= 7; ++k) CHECK(at(c, 1, 12, k) == CellClass::liquid);   // beside it
    CHECK(at(c, 12, 12, 16) == CellClass::air);
    CHECK(c.count(CellClass::liquid) >= std::size_t(22 * 22 * 6));
}

TEST_CASE("the fill is the same for every thread count", "[interior_fill][threads]") {
    const FluidDomain domain = closed_domain(24);
    const std::vector<float> particles = particles_where(24, [](double x, double y, double z) {
        const double r = sphere_distance(x, y, z, 8, 12, 16);
        return pool_band(x, y, z) || (r > 2 && r < 5);
    });
    const InteriorFill one = fill_interior(view(particles), domain, 0.5 * kCell, 1, 0);
    REQUIRE(!one.source.empty());
    for (int threads : {2, 3, 7}) {
        const InteriorFill many = fill_interior(view(particles), domain, 0.5 * kCell, threads, 0);
        CHECK(many.positions == one.positions);
        CHECK(many.source == one.source);
        CHECK(many.classification.cells == one.classification.cells);
    }
}

TEST_CASE("the pipeline fills a narrow band into solid water, on request or by itself for a narrow band", "[interior_fill][pipeline]") {
    FluidDomain domain = closed_domain(24);
    const std::vector<float> particles = particles_where(24, pool_band);
    PipelineOptions options;
    options.reconstruction.particle_radius = 0.25 * kCell;
    options.execution.threads = 2;
    const PipelineResult hollow = run_pipeline(view(particles), {}, options);  // no domain: the band alone

    options.fluid_domain = &domain;
    options.reconstruction.fluid_surface = 0;  // the SPH surface (automatic would take Mantaflow's level set)
    const PipelineResult solid = run_pipeline(view(particles), {}, options);  // automatic: a narrow band, filled
    // The pool: 22 x 22 cells inside the walls, about 11 cells deep (the band's top at 12, the floor's wall at 1).
    const double pool = 22 * 22 * 11 * kCell * kCell * kCell;
    CHECK(mesh_volume(solid.mesh) == Approx(pool).epsilon(0.05));
    CHECK(mesh_volume(hollow.mesh) < 0.5 * pool);
    CHECK(solid.stats.count("interior_fill_particles", -1.0) > 0);

    options.reconstruction.fill_interior = 0;
    CHECK(mesh_volume(run_pipeline(view(particles), {}, options).mesh) == Approx(mesh_volume(hollow.mesh)));

    domain.band_width_cells = 0.0;  // the whole liquid has particles: automatic does not fill
    options.reconstruction.fill_interior = -1;
    CHECK(run_pipeline(view(particles), {}, options).stats.count("interior_fill_particles", -1.0) == -1.0);
}

TEST_CASE("particles and obstacles far outside the grid, or not finite, are left out", "[interior_fill][bad-input]") {
    FluidDomain domain = closed_domain(24);
    std::vector<float> particles = particles_where(24, pool_band);
    const InteriorFill reference = fill_interior(view(particles), domain, 0.5 * kCell, 2, 0);
    const float far = 1e30f, nan = std::numeric_limits<float>::quiet_NaN();
    particles.insert(particles.end(), {far, far, far, -far, 0.5f, 0.5f, nan, 0.5f, 0.5f});
    domain.obstacles.push_back({far, far, far, -far, far, far, far, -far, far});
    const InteriorFill fill = fill_interior(view(particles), domain, 0.5 * kCell, 2, 0);
    CHECK(fill.classification.cells == reference.classification.cells);
    CHECK(fill.positions == reference.positions);
}

TEST_CASE("the fill refuses what it cannot use, naming it", "[interior_fill][bad-input]") {
    const std::vector<float> particles = particles_where(8, [](double, double, double z) { return z < 3; });
    PipelineOptions options;
    options.reconstruction.particle_radius = 0.25 * kCell;
    options.reconstruction.fill_interior = 1;
    CHECK_THROWS_WITH(run_pipeline(view(particles), {}, options), Catch::Contains("fill_interior is on") && Catch::Contains("fluid domain"));

    FluidDomain domain = closed_domain(8);
    options.fluid_domain = &domain;
    domain.resolution = {8, 0, 8};
    CHECK_THROWS_WITH(run_pipeline(view(particles), {}, options), Catch::Contains("fluid_domain.resolution"));
    domain = closed_domain(8);
    domain.axes[2] = {0.0, 0.0, 0.0};
    CHECK_THROWS_WITH(run_pipeline(view(particles), {}, options), Catch::Contains("fluid_domain.axes"));
    domain = closed_domain(8);
    domain.gravity = {0.0, 0.0, 0.0};
    CHECK_THROWS_WITH(run_pipeline(view(particles), {}, options), Catch::Contains("fluid_domain.gravity"));
    domain = closed_domain(8);
    domain.obstacles = {std::vector<float>(10, 0.0f)};
    CHECK_THROWS_WITH(run_pipeline(view(particles), {}, options), Catch::Contains("fluid_domain.obstacles[0]"));
}
