// Mantaflow's own surface (surface/particle_level_set.h) on hand-made narrow bands: a closed, finite mesh near its
// particles that encloses what the band encloses, the same for any thread count, bad settings refused by name.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

#include "band_particles.h"
#include "base/errors.h"
#include "mesh/components.h"
#include "mesh/topology.h"
#include "pipeline.h"
#include "surface/particle_level_set.h"

using namespace meniscus;

namespace {

constexpr double kCell = 0.1;
constexpr int kCells = 20;

FluidDomain closed_domain() {
    FluidDomain d;
    d.axes = {{{kCell, 0, 0}, {0, kCell, 0}, {0, 0, kCell}}};
    d.resolution = {kCells, kCells, kCells};
    d.band_width_cells = 2.0;
    return d;
}

// A drop of radius 7 cells at the domain's centre, as a narrow band keeps it: 2 x 2 x 2 particles in each cell whose
// centre lies in its outer 2 cells, jittered a little (deterministically).
std::vector<float> drop_band() {
    return test::band_particles(kCells, kCell, 777u, [](double x, double y, double z) {
        const double r = std::sqrt((x - 10) * (x - 10) + (y - 10) * (y - 10) + (z - 10) * (z - 10));
        return r >= 5.0 && r <= 7.0;
    });
}

PositionsView view(const std::vector<float>& p) { return PositionsView(p.data(), p.size() / 3); }

}  // namespace

TEST_CASE("a drop's band gives one closed surface around it, near its particles", "[particle_level_set]") {
    const FluidDomain domain = closed_domain();
    const std::vector<float> particles = drop_band();
    const std::vector<float> speed(particles.size() / 3, 2.5f);
    const ParticleLevelSetSurface surface = particle_level_set_surface(view(particles), {{"speed", speed.data(), 1, false}}, domain, 2, 0);
    const TriMesh& mesh = surface.mesh;
    REQUIRE(mesh.num_triangles() > 100);
    const MeshCheck check = check_mesh(mesh);
    CHECK(check.closed());
    CHECK(check.manifold());
    CHECK(check.oriented());
    CHECK(check.non_finite_vertices == 0);
    // One component: the band's inside is joined as water, no inner surface.
    int32_t components = 0;
    component_labels(mesh, &components);
    CHECK(components == 1);
    CHECK(surface.joined_cells > 0);
    // Every vertex lies just outside the outermost particles (radius 7 cells), within Mantaflow's particle radius.
    double nearest = std::numeric_limits<double>::infinity(), furthest = 0.0;
    for (std::size_t v = 0; v < mesh.num_vertices(); ++v) {
        double r2 = 0.0;
        for (int a = 0; a < 3; ++a) r2 += (mesh.vertices[3 * v + a] - 10 * kCell) * (mesh.vertices[3 * v + a] - 10 * kCell);
        nearest = std::min(nearest, std::sqrt(r2) / kCell);
        furthest = std::max(furthest, std::sqrt(r2) / kCell);
    }
    CHECK(nearest > 6.5);
    CHECK(furthest < 8.0);
    // The attribute is the particles' weighted mean: the same everywhere.
    REQUIRE(mesh.attributes.size() == 1);
    for (float s : mesh.attributes[0].values) CHECK(s == Approx(2.5f));
}

TEST_CASE("the level set's mesh is the same for any thread count", "[particle_level_set][threads]") {
    const FluidDomain domain = closed_domain();
    const std::vector<float> particles = drop_band();
    std::vector<float> index(particles.size() / 3);
    for (std::size_t p = 0; p < index.size(); ++p) index[p] = float(p);
    const std::vector<AttributeInput> attributes{{"index", index.data(), 1, false}, {"id", index.data(), 1, true}};
    const ParticleLevelSetSurface one = particle_level_set_surface(view(particles), attributes, domain, 1, 0);
    for (int threads : {2, 3}) {
        const ParticleLevelSetSurface many = particle_level_set_surface(view(particles), attributes, domain, threads, 0);
        CHECK(many.mesh.vertices == one.mesh.vertices);
        CHECK(many.mesh.triangles == one.mesh.triangles);
        for (std::size_t a = 0; a < attributes.size(); ++a) CHECK(many.mesh.attributes[a].values == one.mesh.attributes[a].values);
    }
}

TEST_CASE("the pipeline takes Mantaflow's surface for a narrow band, the SPH surface on request", "[particle_level_set][pipeline]") {
    const FluidDomain domain = closed_domain();
    const std::vector<float> particles = drop_band();
    PipelineOptions options;
    options.reconstruction.particle_radius = 0.25 * kCell;
    options.execution.threads = 2;
    options.fluid_domain = &domain;
    CHECK(run_pipeline(view(particles), {}, options).stats.count("level_set_cells", -1.0) == 40.0 * 40 * 40);
    options.reconstruction.fluid_surface = 0;
    CHECK(run_pipeline(view(particles), {}, options).stats.count("level_set_cells", -1.0) == -1.0);
    options.fluid_domain = nullptr;
    options.reconstruction.fluid_surface = 1;
    CHECK_THROWS_WITH(run_pipeline(view(particles), {}, options), Catch::Contains("fluid_surface is 1") && Catch::Contains("fluid domain"));
}

TEST_CASE("Mantaflow's mesh settings out of range are refused by name", "[particle_level_set][bad-input]") {
    const std::vector<float> particles = drop_band();
    FluidDomain domain = closed_domain();
    domain.mesh_upres = 0;
    CHECK_THROWS_AS(particle_level_set_surface(view(particles), {}, domain, 1, 0), InputError);
    CHECK_THROWS_WITH(particle_level_set_surface(view(particles), {}, domain, 1, 0), Catch::Contains("fluid_domain.mesh_upres"));
    domain = closed_domain();
    domain.mesh_particle_radius = std::numeric_limits<double>::quiet_NaN();
    CHECK_THROWS_WITH(particle_level_set_surface(view(particles), {}, domain, 1, 0), Catch::Contains("fluid_domain.mesh_particle_radius"));
    domain = closed_domain();
    domain.mesh_smoothen_neg = -1;
    CHECK_THROWS_WITH(particle_level_set_surface(view(particles), {}, domain, 1, 0), Catch::Contains("fluid_domain.mesh_smoothen_neg"));
    domain = closed_domain();
    domain.mesh_concave_lower = 4.0;
    CHECK_THROWS_WITH(particle_level_set_surface(view(particles), {}, domain, 1, 0), Catch::Contains("fluid_domain.mesh_concave_lower"));
    domain = closed_domain();
    domain.mesh_upres = 16;  // 320^3 cells: over a 1 MiB budget
    CHECK_THROWS_AS(particle_level_set_surface(view(particles), {}, domain, 1, 1u << 20), ResourceError);
}
