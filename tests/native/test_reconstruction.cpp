// Reconstruction core: kernel, neighbour search, marching cubes, the particle-to-mesh path, determinism and
// refusals of bad input.
#include <catch2/catch.hpp>

#include <cmath>
#include <cstring>
#include <random>
#include <string>
#include <vector>

#include "base/numbers.h"
#include "base/errors.h"
#include "io/io.h"
#include "sph/kernel.h"
#include "surface/marching_cubes.h"
#include "mesh/adjacency.h"
#include "sph/neighborhood.h"
#include "pipeline.h"
#include "post/postprocess.h"
#include "surface/reconstruction.h"

using namespace meniscus;

namespace {

std::string shared(const std::string& name) { return std::string(MENISCUS_SHARED_DATA) + "/" + name; }

uint64_t mesh_hash(const TriMesh& mesh) {
    uint64_t h = 1469598103934665603ull;
    auto mix = [&](uint32_t v) { h = (h ^ v) * 1099511628211ull; };
    for (float v : mesh.vertices) {
        uint32_t bits;
        std::memcpy(&bits, &v, 4);
        mix(bits);
    }
    for (int32_t t : mesh.triangles) mix(static_cast<uint32_t>(t));
    return h;
}

double signed_volume(const TriMesh& m) {
    double volume = 0.0;
    for (std::size_t t = 0; t < m.num_triangles(); ++t) {
        const float* a = &m.vertices[3 * m.triangles[3 * t]];
        const float* b = &m.vertices[3 * m.triangles[3 * t + 1]];
        const float* c = &m.vertices[3 * m.triangles[3 * t + 2]];
        volume += (double(a[0]) * (double(b[1]) * c[2] - double(b[2]) * c[1]) - double(a[1]) * (double(b[0]) * c[2] - double(b[2]) * c[0]) +
                   double(a[2]) * (double(b[0]) * c[1] - double(b[1]) * c[0])) / 6.0;
    }
    return volume;
}

ReconstructionParams params(double radius, double cube) {
    ReconstructionParams p;
    p.particle_radius = radius;
    p.cube_size = cube;
    return p;
}

}  // namespace

TEST_CASE("cubic spline kernel integrates to one and vanishes at the support", "[kernel]") {
    for (double support : {0.1, 1.0, 4.0}) {
        CubicSplineKernel kernel(support);
        const int steps = 20000;
        double integral = 0.0;
        for (int i = 0; i < steps; ++i) {
            const double d = (i + 0.5) * support / steps;
            integral += 4.0 * kPi * d * d * kernel.value(static_cast<float>(d)) * support / steps;
        }
        CHECK(integral == Approx(1.0).epsilon(1e-4));
        CHECK(kernel.value(static_cast<float>(support)) == 0.0f);
        CHECK(kernel.value(static_cast<float>(0.5 * support)) > 0.0f);
        // The derivative matches a finite difference.
        const float d = static_cast<float>(0.3 * support), h = static_cast<float>(1e-3 * support);
        CHECK(kernel.derivative(d) == Approx((kernel.value(d + h) - kernel.value(d - h)) / (2 * h)).epsilon(1e-2));
    }
}

TEST_CASE("neighbour search finds exactly the brute-force neighbours", "[neighborhood]") {
    std::mt19937 rng(7);
    std::uniform_real_distribution<float> u(-1.0f, 1.0f);
    std::vector<float> points(3 * 3000);
    for (float& x : points) x = u(rng);
    const float radius = 0.15f;
    ParticleGrid grid(PositionsView(points.data(), 3000), radius, 2);
    REQUIRE(grid.size() == 3000);
    for (int q = 0; q < 200; ++q) {
        const float x[3] = {u(rng), u(rng), u(rng)};
        std::vector<uint32_t> found, expected;
        grid.for_each_neighbor(x, radius, [&](std::size_t j, float) { found.push_back(grid.original_index(j)); });
        for (uint32_t i = 0; i < 3000; ++i) {
            const float dx = x[0] - points[3 * i], dy = x[1] - points[3 * i + 1], dz = x[2] - points[3 * i + 2];
            if (dx * dx + dy * dy + dz * dz < radius * radius) expected.push_back(i);
        }
        std::sort(found.begin(), found.end());
        REQUIRE(found == expected);
    }
}

TEST_CASE("marching cubes table: every case is closed and consistently oriented", "[mc]") {
    // Each case's triangles must pair every interior edge with its reverse, and the edges left over must lie on
    // cube faces: checked through whole meshes below; here, each case has at most 4 loop centres and no triangle
    // repeats an edge vertex.
    for (unsigned inside = 0; inside < 256; ++inside)
        for (unsigned joined = 0; joined < 64; ++joined) {
            const mc::Case& c = mc::lookup(inside, joined);
            for (int t = 0; t < c.triangle_count; ++t) {
                const int a = c.edges[3 * t], b = c.edges[3 * t + 1], d = c.edges[3 * t + 2];
                REQUIRE(a != b);
                REQUIRE(b != d);
                REQUIRE(a != d);
            }
            if (inside == 0 || inside == 255) REQUIRE(c.triangle_count == 0);
            else REQUIRE(c.triangle_count > 0);
        }
}

TEST_CASE("marching cubes reproduces a sphere's volume within 1 %", "[mc]") {
    const double radius = 1.0;
    const double lo[3] = {-1.3, -1.3, -1.3}, hi[3] = {1.3, 1.3, 1.3};
    auto field = [&](double x, double y, double z) { return static_cast<float>(radius - std::sqrt(x * x + y * y + z * z)); };
    const TriMesh mesh = marching_cubes_on_function(field, lo, hi, 0.02, 0.0, 2);
    const MeshCheck check = check_mesh(mesh);
    INFO(check.summary());
    REQUIRE(check.ok());
    const double exact = 4.0 / 3.0 * kPi * radius * radius * radius;
    CHECK(signed_volume(mesh) == Approx(exact).epsilon(0.01));
    CHECK(signed_volume(mesh) > 0.0);  // outward orientation
}

TEST_CASE("marching cubes on random fields gives closed, manifold, oriented meshes", "[mc]") {
    for (int seed = 0; seed < 6; ++seed) {
        std::mt19937 rng(seed);
        std::uniform_real_distribution<float> u(0.0f, 1.0f);
        const int n = 24;
        std::vector<float> noise(n * n * n);
        for (float& v : noise) v = u(rng);
        // Random values inside a box, zero on and outside it: every sign configuration and ambiguous face occurs.
        auto field = [&](double x, double y, double z) {
            const long i = std::lround(x / 0.1), j = std::lround(y / 0.1), k = std::lround(z / 0.1);
            if (i < 1 || j < 1 || k < 1 || i >= n - 1 || j >= n - 1 || k >= n - 1) return 0.0f;
            return noise[(k * n + j) * n + i];
        };
        const double lo[3] = {0, 0, 0}, hi[3] = {0.1 * n, 0.1 * n, 0.1 * n};
        const TriMesh mesh = marching_cubes_on_function(field, lo, hi, 0.1, 0.5, seed % 2 + 1);
        const MeshCheck check = check_mesh(mesh);
        INFO("seed " << seed << ": " << check.summary());
        REQUIRE(mesh.num_triangles() > 1000);
        REQUIRE(check.ok());
        REQUIRE(check.unreferenced_vertices == 0);
    }
}

TEST_CASE("a single particle gives one closed blob around it", "[reconstruction]") {
    const float particle[3] = {0.31f, -0.12f, 7.5f};
    PipelineOptions options;
    options.reconstruction = params(0.025, 0.25);
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
    const ParticleData particles = read_particles(shared("splashsurf/double_dam_break_frame_26_4732_particles.vtk"));
    PipelineOptions options;
    options.reconstruction = params(0.025, 0.5);
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
    const ParticleData particles = read_particles(shared("splashsurf/bunny_frame_14_7705_particles.vtk"));
    REQUIRE(particles.size() == 7706);
    const SurfaceReconstruction r = reconstruct_surface(PositionsView(particles.positions.data(), particles.size()), params(0.025, 1.0), {});
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
        const ParticleData particles = read_particles(shared(e.file));
        const SurfaceReconstruction r = reconstruct_surface(PositionsView(particles.positions.data(), particles.size()), params(0.025, e.cube), {});
        INFO(e.file);
        CHECK(r.mesh.num_triangles() >= e.lo);
        CHECK(r.mesh.num_triangles() <= e.hi);
        CHECK(check_mesh(r.mesh).ok());
    }
}

TEST_CASE("float64 and float32 positions give the same mesh", "[reconstruction]") {
    const ParticleData particles = read_particles(shared("splashsurf/double_dam_break_frame_01_4732_particles.vtk"));
    std::vector<double> wide(particles.positions.begin(), particles.positions.end());
    const auto a = reconstruct_surface(PositionsView(particles.positions.data(), particles.size()), params(0.025, 1.0), {});
    const auto b = reconstruct_surface(PositionsView(wide.data(), particles.size()), params(0.025, 1.0), {});
    CHECK(mesh_hash(a.mesh) == mesh_hash(b.mesh));
}

TEST_CASE("far-apart droplets cost what they need, not their bounding box", "[reconstruction][memory]") {
    // Two particles 1000 radii apart on every axis: the grid between them is never allocated.
    const float near_pair[6] = {0.0f, 0.0f, 0.0f, 0.02f, 0.0f, 0.0f};
    const float far_pair[6] = {0.0f, 0.0f, 0.0f, 25.0f, 25.0f, 25.0f};
    PipelineStats near_stats, far_stats;
    const auto near = reconstruct_surface(PositionsView(near_pair, 2), params(0.025, 0.5), {}, &near_stats);
    const auto far = reconstruct_surface(PositionsView(far_pair, 2), params(0.025, 0.5), {}, &far_stats);
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
    CHECK_THAT(message_of(params(0.0, 0.5), one, 1), Catch::Contains("particle_radius"));
    CHECK_THAT(message_of(params(-1.0, 0.5), one, 1), Catch::Contains("particle_radius"));
    CHECK_THAT(message_of(params(0.025, 0.0), one, 1), Catch::Contains("cube_size"));
    ReconstructionParams bad_length = params(0.025, 0.5);
    bad_length.smoothing_length = std::nan("");
    CHECK_THAT(message_of(bad_length, one, 1), Catch::Contains("smoothing_length"));
    REQUIRE_THROWS_AS(reconstruct_surface(PositionsView(one, 1), params(0.0, 0.5), {}), InputError);

    const float with_nan[9] = {0, 0, 0, NAN, 0, 0, 0, INFINITY, 0};
    CHECK_THAT(message_of(params(0.025, 0.5), with_nan, 3), Catch::Contains("2 of 3 particles have NaN or Inf"));
    ExecutionOptions skip;
    skip.skip_invalid = true;
    PipelineStats stats;
    const auto kept = reconstruct_surface(PositionsView(with_nan, 3), params(0.025, 0.5), skip, &stats);
    CHECK(kept.grid.size() == 1);
    REQUIRE(stats.warnings.size() == 1);

    // A cube size whose grid would exhaust memory is refused before allocating, with the estimate.
    const std::string huge = message_of(params(0.025, 1e-4), one, 1);
    CHECK_THAT(huge, Catch::Contains("would need about"));
    REQUIRE_THROWS_AS(reconstruct_surface(PositionsView(one, 1), params(0.025, 1e-4), {}), ResourceError);

    // Zero particles: an empty mesh, not an error.
    const auto empty = reconstruct_surface(PositionsView(one, 0), params(0.025, 0.5), {});
    CHECK(empty.mesh.num_triangles() == 0);
}

TEST_CASE("attributes are interpolated with the Shepard correction", "[reconstruction][attributes]") {
    const ParticleData particles = read_particles(shared("splashsurf/bunny_frame_14_7705_particles.vtk"));
    // A constant attribute must come out exactly constant (0th-order correction), a linear one close to linear.
    std::vector<float> constant(particles.size() * 3, 0.0f), linear(particles.size());
    for (std::size_t i = 0; i < particles.size(); ++i) {
        constant[3 * i] = 2.5f;
        constant[3 * i + 1] = -1.0f;
        linear[i] = particles.positions[3 * i + 2];
    }
    PipelineOptions options;
    options.reconstruction = params(0.025, 1.0);
    const PipelineResult result = run_pipeline(PositionsView(particles.positions.data(), particles.size()),
                                               {{"c", constant.data(), 3}, {"z", linear.data(), 1}}, options);
    REQUIRE(result.mesh.attributes.size() == 2);
    const Attribute& c = result.mesh.attributes[0];
    const Attribute& z = result.mesh.attributes[1];
    REQUIRE(c.count() == result.mesh.num_vertices());
    double worst = 0.0, mean_error = 0.0;
    for (std::size_t v = 0; v < result.mesh.num_vertices(); ++v) {
        worst = std::max(worst, std::fabs(c.values[3 * v] - 2.5));
        mean_error += std::fabs(z.values[v] - result.mesh.vertices[3 * v + 2]) / double(result.mesh.num_vertices());
    }
    CHECK(worst < 1e-5);
    CHECK(mean_error < 0.05);  // within the kernel support (0.1)
}

TEST_CASE("decimation of real marching-cubes meshes hands over the adjacency a rebuild gives", "[reconstruction][post]") {
    // Droplets (single particles and pairs) at c = 1.0: their blobs carry several barnacles each, close together,
    // so later decimation passes run on patched adjacencies.
    std::mt19937 random(7);
    std::uniform_real_distribution<float> offset(0.0f, 0.05f);
    std::normal_distribution<float> partner(0.0f, 0.025f);
    std::vector<float> positions;
    for (int i = 0; i < 10; ++i)
        for (int j = 0; j < 10; ++j)
            for (int k = 0; k < 2; ++k) {
                const float c[3] = {i * 0.3f + offset(random), j * 0.3f + offset(random), k * 0.3f + offset(random)};
                positions.insert(positions.end(), c, c + 3);
                if ((i + j + k) % 2)
                    for (int a = 0; a < 3; ++a) positions.push_back(c[a] + partner(random));
            }
    SurfaceReconstruction r = reconstruct_surface(PositionsView(positions.data(), positions.size() / 3), params(0.025, 1.0), {});
    MeshAdjacency handed;
    REQUIRE(decimate_barnacles(r.mesh, 2, &handed) > 5);
    const MeshAdjacency rebuilt = build_adjacency(r.mesh, 1);
    REQUIRE(handed.vertex_triangles.rows() == r.mesh.num_vertices());
    CHECK(handed.vertex_triangles.offsets == rebuilt.vertex_triangles.offsets);
    CHECK(handed.vertex_triangles.items == rebuilt.vertex_triangles.items);
    CHECK(handed.vertex_neighbours.offsets == rebuilt.vertex_neighbours.offsets);
    CHECK(handed.vertex_neighbours.items == rebuilt.vertex_neighbours.items);
    CHECK(count_single_vertex_configurations(r.mesh) == 0);
    CHECK(count_double_vertex_configurations(r.mesh) == 0);
    CHECK(check_mesh(r.mesh).ok());
}
