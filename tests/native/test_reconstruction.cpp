// The particle-to-mesh path (surface/reconstruction.h, pipeline.h): published triangle ranges of the shared frames,
// determinism, memory that follows the fluid, refusals of bad input.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <set>
#include <string>
#include <vector>

#include "analysis/quality.h"
#include "base/errors.h"
#include "io/io.h"
#include "mesh/topology.h"
#include "mesh_builders.h"
#include "pipeline.h"
#include "surface/level_set.h"
#include "surface/reconstruction.h"

using namespace meniscus;
using namespace meniscus::test;

TEST_CASE("a single particle gives one closed blob around it", "[reconstruction]") {
    const float particle[3] = {0.31f, -0.12f, 7.5f};
    PipelineOptions options;
    options.reconstruction = reconstruction_params(0.025, 0.25);
    options.postprocess.normals = true;
    const PipelineResult result = run_pipeline(PositionsView(particle, 1), {}, options);
    const MeshQuality quality = assess_quality(result.mesh);
    INFO(quality.check.summary());
    REQUIRE(quality.check.ok());
    REQUIRE(quality.components.size() == 1);
    CHECK(quality.volume > 0.0);
    // The blob is centred on the particle and smaller than the kernel support.
    double centre[3] = {0, 0, 0};
    for (std::size_t v = 0; v < result.mesh.num_vertices(); ++v)
        for (int k = 0; k < 3; ++k) centre[k] += result.mesh.vertices[3 * v + k] / double(result.mesh.num_vertices());
    for (int k = 0; k < 3; ++k) CHECK(centre[k] == Approx(particle[k]).margin(0.01));
}

TEST_CASE("the same mesh, bit for bit, for 1 and 2 threads", "[reconstruction][determinism]") {
    const ParticleData particles = read_particles(shared_frame("splashsurf/double_dam_break_frame_26_4732_particles.vtk"));
    PipelineOptions options;
    options.reconstruction = reconstruction_params(0.025, 0.5);
    options.postprocess.decimate_barnacles = true;
    options.postprocess.smoothing_iterations = 25;
    options.postprocess.normal_smoothing_iterations = 10;
    options.execution.threads = 1;
    const PipelineResult one = run_pipeline(PositionsView(particles.positions.data(), particles.size()), {}, options);
    options.execution.threads = 2;
    const PipelineResult two = run_pipeline(PositionsView(particles.positions.data(), particles.size()), {}, options);
    REQUIRE(one.mesh.num_triangles() > 0);
    CHECK(mesh_hash(one.mesh) == mesh_hash(two.mesh));
    CHECK(one.mesh.normals == two.mesh.normals);
}

TEST_CASE("bunny frame: 35 000 - 40 000 triangles, closed and manifold (splashsurf's published range)", "[reconstruction][data]") {
    const ParticleData particles = read_particles(shared_frame("splashsurf/bunny_frame_14_7705_particles.vtk"));
    REQUIRE(particles.size() == 7706);
    const SurfaceReconstruction r = reconstruct_surface(PositionsView(particles.positions.data(), particles.size()), reconstruction_params(0.025, 1.0), {});
    const MeshCheck check = check_mesh(r.mesh);
    INFO(check.summary());
    CHECK(r.mesh.num_triangles() >= 35000);
    CHECK(r.mesh.num_triangles() <= 40000);
    CHECK(check.ok());
    CHECK(signed_volume(r.mesh) > 0.0);
}

TEST_CASE("published triangle ranges of the other shared frames", "[reconstruction][data]") {
    struct Expected {
        const char* file;
        double cube;
        std::size_t lo, hi;
    };
    for (const Expected& e : {Expected{"splashsurf/hilbert2_7954_particles.vtk", 1.1, 90000, 100000},
                              Expected{"splashsurf/bunny_frame_14_7705_particles.vtk", 0.75, 60000, 80000}}) {
        const ParticleData particles = read_particles(shared_frame(e.file));
        const SurfaceReconstruction r = reconstruct_surface(PositionsView(particles.positions.data(), particles.size()), reconstruction_params(0.025, e.cube), {});
        INFO(e.file);
        CHECK(r.mesh.num_triangles() >= e.lo);
        CHECK(r.mesh.num_triangles() <= e.hi);
        CHECK(check_mesh(r.mesh).ok());
    }
}

TEST_CASE("float64 and float32 positions give the same mesh", "[reconstruction]") {
    const ParticleData particles = read_particles(shared_frame("splashsurf/double_dam_break_frame_01_4732_particles.vtk"));
    std::vector<double> wide(particles.positions.begin(), particles.positions.end());
    const auto a = reconstruct_surface(PositionsView(particles.positions.data(), particles.size()), reconstruction_params(0.025, 1.0), {});
    const auto b = reconstruct_surface(PositionsView(wide.data(), particles.size()), reconstruction_params(0.025, 1.0), {});
    CHECK(mesh_hash(a.mesh) == mesh_hash(b.mesh));
}

TEST_CASE("far-apart droplets cost what they need, not their bounding box", "[reconstruction][memory]") {
    // Two particles 1000 radii apart on every axis: the grid between them is never allocated.
    const float near_pair[6] = {0.0f, 0.0f, 0.0f, 0.02f, 0.0f, 0.0f};
    const float far_pair[6] = {0.0f, 0.0f, 0.0f, 25.0f, 25.0f, 25.0f};
    PipelineStats near_stats, far_stats;
    const auto near = reconstruct_surface(PositionsView(near_pair, 2), reconstruction_params(0.025, 0.5), {}, &near_stats);
    const auto far = reconstruct_surface(PositionsView(far_pair, 2), reconstruction_params(0.025, 0.5), {}, &far_stats);
    auto bricks = [](const PipelineStats& s) {
        for (const auto& c : s.counts)
            if (c.first == "active_bricks") return c.second;
        return -1.0;
    };
    CHECK(bricks(far_stats) <= 2 * 8);  // at most 8 bricks around each particle
    CHECK(bricks(far_stats) >= bricks(near_stats));
    CHECK(check_mesh(far.mesh).ok());
    CHECK(assess_quality(far.mesh).components.size() == 2);
}

TEST_CASE("bad input is refused with a message naming it", "[reconstruction][errors]") {
    const float one[3] = {0, 0, 0};
    auto message_of = [&](ReconstructionParams p, const float* data, std::size_t n, ExecutionOptions e = {}) {
        try {
            reconstruct_surface(PositionsView(data, n), p, e);
        } catch (const std::exception& error) {
            return std::string(error.what());
        }
        return std::string();
    };
    CHECK_THAT(message_of(reconstruction_params(0.0, 0.5), one, 1), Catch::Contains("particle_radius"));
    CHECK_THAT(message_of(reconstruction_params(-1.0, 0.5), one, 1), Catch::Contains("particle_radius"));
    CHECK_THAT(message_of(reconstruction_params(0.025, 0.0), one, 1), Catch::Contains("cube_size"));
    ReconstructionParams bad_length = reconstruction_params(0.025, 0.5);
    bad_length.smoothing_length = std::nan("");
    CHECK_THAT(message_of(bad_length, one, 1), Catch::Contains("smoothing_length"));
    REQUIRE_THROWS_AS(reconstruct_surface(PositionsView(one, 1), reconstruction_params(0.0, 0.5), {}), InputError);

    const float with_nan[9] = {0, 0, 0, NAN, 0, 0, 0, INFINITY, 0};
    CHECK_THAT(message_of(reconstruction_params(0.025, 0.5), with_nan, 3), Catch::Contains("2 of 3 particles have NaN or Inf"));
    ExecutionOptions skip;
    skip.skip_invalid = true;
    PipelineStats stats;
    const auto kept = reconstruct_surface(PositionsView(with_nan, 3), reconstruction_params(0.025, 0.5), skip, &stats);
    CHECK(kept.grid.size() == 1);
    REQUIRE(stats.warnings.size() == 1);

    // A cube size whose grid would exhaust memory is refused before allocating, with the estimate.
    const std::string huge = message_of(reconstruction_params(0.025, 1e-4), one, 1);
    CHECK_THAT(huge, Catch::Contains("would need about"));
    REQUIRE_THROWS_AS(reconstruct_surface(PositionsView(one, 1), reconstruction_params(0.025, 1e-4), {}), ResourceError);

    // Zero particles: an empty mesh, not an error.
    const auto empty = reconstruct_surface(PositionsView(one, 0), reconstruction_params(0.025, 0.5), {});
    CHECK(empty.mesh.num_triangles() == 0);
}

TEST_CASE("the bricks near particles: every brick a cell's particles reach, sorted, once; dense and sparse frames", "[reconstruction][threads]") {
    const double support = 0.1, cube = 0.0125;
    // Their definition: the bricks of lattice cubes within support + one cube of each occupied cell.
    auto expected_bricks = [&](const ParticleGrid& grid) {
        std::set<LatticeCoords, bool (*)(const LatticeCoords&, const LatticeCoords&)> bricks(coords_less);
        const double cell = grid.cell_size(), margin = support + cube;
        for (std::size_t c = 0; c < grid.num_cells(); ++c) {
            const auto coords = grid.cell_coords(c);
            LatticeCoords lo, hi;
            for (int k = 0; k < 3; ++k) {
                lo[k] = floor_div(static_cast<int64_t>(std::floor((double(coords[k]) * cell - margin) / cube)), kBrick);
                hi[k] = floor_div(static_cast<int64_t>(std::ceil((double(coords[k] + 1) * cell + margin) / cube)), kBrick);
            }
            for (int64_t z = lo[2]; z <= hi[2]; ++z)
                for (int64_t y = lo[1]; y <= hi[1]; ++y)
                    for (int64_t x = lo[0]; x <= hi[0]; ++x) bricks.insert({x, y, z});
        }
        return std::vector<LatticeCoords>(bricks.begin(), bricks.end());
    };
    // A compact block with negative coordinates (flags over the bricks' box), then the same with two droplets far
    // apart along a diagonal (a box far too sparse to flag: the bricks are listed and sorted).
    std::vector<float> positions;
    for (int i = 0; i < 40; ++i)
        for (int j = 0; j < 30; ++j)
            for (int k = 0; k < 20; ++k)
                for (float x : {-0.6f + 0.025f * i, -0.3f + 0.025f * j, 0.1f + 0.025f * k}) positions.push_back(x);
    for (bool sparse : {false, true}) {
        if (sparse)
            for (float x : {900.0f, -700.0f, 650.0f, -800.0f, 750.0f, -900.0f}) positions.push_back(x);
        const ParticleGrid grid(PositionsView(positions.data(), positions.size() / 3), support, 2);
        const std::vector<LatticeCoords> expected = expected_bricks(grid);
        REQUIRE(expected.size() > 8);
        for (int threads : {1, 2, 3, 7}) {
            INFO((sparse ? "sparse, " : "dense, ") << threads << " threads");
            CHECK(bricks_near_particles(grid, support, cube, threads) == expected);
        }
    }
}
