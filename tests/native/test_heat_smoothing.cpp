// The smoothing of a physical reach (the default; smoothing_reach 0: the paper's iterations): heat flow with local volume return
// (post/heat_smoothing.h), and the measures at a physical scale (analysis/scale_metrics.h).
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

#include "analysis/quality.h"
#include "analysis/scale_metrics.h"
#include "base/errors.h"
#include "base/numbers.h"
#include "mesh/adjacency.h"
#include "mesh/components.h"
#include "mesh/topology.h"
#include "mesh_builders.h"
#include "pipeline.h"
#include "post/heat_smoothing.h"
#include "post/smoothing.h"
#include "post/volume.h"
#include "post/wall_constraints.h"

using namespace meniscus;
using namespace meniscus::test;

namespace {

constexpr double kRadius = 0.025;

// A regular triangulated square [0, size]^2 (edge `edge`, every cell split along the same diagonal) carrying
// z = amplitude sin(2 pi x / wavelength); open, so only the interior is measured.
TriMesh wavy_plane(double size, double edge, double wavelength, double amplitude) {
    TriMesh m;
    const int n = static_cast<int>(std::lround(size / edge));
    for (int j = 0; j <= n; ++j)
        for (int i = 0; i <= n; ++i) add_vertex(m, {i * edge, j * edge, amplitude * std::sin(2.0 * kPi * i * edge / wavelength)});
    auto id = [&](int i, int j) { return static_cast<int32_t>(j * (n + 1) + i); };
    for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i) {
            add_triangle(m, id(i, j), id(i + 1, j), id(i + 1, j + 1));
            add_triangle(m, id(i, j), id(i + 1, j + 1), id(i, j + 1));
        }
    return m;
}

// Amplitude of the sine left in the middle third of the plane (least squares against sin).
double sine_amplitude(const TriMesh& m, double size, double wavelength) {
    double num = 0.0, den = 0.0;
    for (std::size_t v = 0; v < m.num_vertices(); ++v) {
        const double x = m.vertices[3 * v], y = m.vertices[3 * v + 1], z = m.vertices[3 * v + 2];
        if (x < size / 3 || x > 2 * size / 3 || y < size / 3 || y > 2 * size / 3) continue;
        const double s = std::sin(2.0 * kPi * x / wavelength);
        num += z * s, den += s * s;
    }
    return num / den;
}

// A jittered lattice slab (a pool), optionally a three-particle-wide tube above it and one isolated particle.
std::vector<float> scene(bool tube, bool droplet) {
    std::mt19937 rng(7);
    std::uniform_real_distribution<float> jitter(-0.1f * 2 * kRadius, 0.1f * 2 * kRadius);
    std::vector<float> p;
    const float s = 2 * kRadius;
    for (int z = 0; z < 6; ++z)
        for (int y = 0; y < 20; ++y)
            for (int x = 0; x < 20; ++x) p.insert(p.end(), {x * s + jitter(rng), y * s + jitter(rng), z * s + jitter(rng)});
    if (tube)
        for (int x = 0; x < 20; ++x)
            for (int y = 0; y < 3; ++y)
                for (int z = 0; z < 3; ++z) p.insert(p.end(), {x * s + jitter(rng), 0.4f + y * s + jitter(rng), 0.8f + z * s + jitter(rng)});
    if (droplet) p.insert(p.end(), {0.5f, 0.5f, 1.5f});
    return p;
}

PipelineOptions options(double cube, int threads) {
    PipelineOptions o;
    o.reconstruction = {kRadius, 2.0, cube, 0.6};
    o.execution.threads = threads;
    o.keep_raw_mesh = true;
    CHECK(o.postprocess.smoothing_reach == kMeasuredReach);  // the default: the setting README's figures were measured with
    return o;
}

PipelineResult run(const std::vector<float>& p, const PipelineOptions& o) { return run_pipeline(PositionsView(p.data(), p.size() / 3), {}, o); }

std::vector<double> sorted_volumes(const TriMesh& m) {
    int32_t count = 0;
    const auto labels = component_labels(m, &count);
    auto v = component_volumes(m, labels, count);
    std::sort(v.begin(), v.end());
    return v;
}

// Volume of the middle third of scene()'s tube (axis y = 0.45, z = 0.85; x in [0.15, 0.35], away from its caps,
// the pool and the droplet). Divergence theorem with F = (0, y - 0.45, z - 0.85) / 2: F has no x component, so the
// cut faces at x = 0.15 and 0.35 add nothing and the tube's own triangles there (by centroid; F is linear, so the
// centroid integrates it exactly) give the slab's volume. The same triangles for the raw and the smoothed mesh.
double tube_section_volume(const TriMesh& m) {
    double volume = 0.0;
    std::size_t used = 0;
    for (std::size_t t = 0; t < m.num_triangles(); ++t) {
        const float* p[3];
        for (int i = 0; i < 3; ++i) p[i] = &m.vertices[3 * static_cast<std::size_t>(m.triangles[3 * t + i])];
        const double cx = (p[0][0] + p[1][0] + p[2][0]) / 3.0, cy = (p[0][1] + p[1][1] + p[2][1]) / 3.0 - 0.45,
                     cz = (p[0][2] + p[1][2] + p[2][2]) / 3.0 - 0.85;
        if (cx < 0.15 || cx > 0.35 || std::hypot(cy, cz) > 0.2) continue;
        const double u[3] = {double(p[1][0]) - p[0][0], double(p[1][1]) - p[0][1], double(p[1][2]) - p[0][2]};
        const double v[3] = {double(p[2][0]) - p[0][0], double(p[2][1]) - p[0][1], double(p[2][2]) - p[0][2]};
        const double ny = u[2] * v[0] - u[0] * v[2], nz = u[0] * v[1] - u[1] * v[0];  // twice the area times n
        volume += 0.25 * (cy * ny + cz * nz);
        ++used;
    }
    REQUIRE(used > 10);
    return volume;
}

}  // namespace

TEST_CASE("heat coefficients keep constants, match the heat kernel, and need ~sqrt(N) terms", "[heat]") {
    for (double n : {3.0, 25.0, 200.0}) {
        const auto c = heat_coefficients(n, 1e-3);
        double sum = 0.0;
        for (double x : c) {
            sum += x;
            CHECK(x > -1e-12);  // the heat kernel's coefficients are positive: the sum is a convex combination
        }
        CHECK(sum == Approx(1.0).margin(1e-12));
        for (double y : {-0.9, 0.0, 0.8, 0.99}) {
            double value = 0.0;
            for (std::size_t k = 0; k < c.size(); ++k) value += c[k] * std::cos(double(k) * std::acos(y));
            CHECK(value == Approx(std::exp(n * (y - 1.0))).margin(2e-3));
        }
        CHECK(c.size() < 8 * std::sqrt(n) + 12);
    }
}

TEST_CASE("the reach is the same up to c = 0.5 and grows with the cube above it", "[heat]") {
    CHECK(smoothing_reach_at(4.0, 0.25) == 4.0);
    CHECK(smoothing_reach_at(4.0, 0.5) == 4.0);
    CHECK(smoothing_reach_at(4.0, 1.0) == Approx(8.0));
    CHECK(smoothing_reach_at(0.0, 1.0) == 0.0);
    CHECK(kMeasuredReach == Approx(4.28));
}

TEST_CASE("heat smoothing: the same physical result for any edge length", "[heat]") {
    // A sine of wavelength 12 r smoothed with reach 4 r (no volume terms) on planes with edges 0.27 r and 0.54 r
    // (c = 0.25 and 0.5): the same attenuation, the heat kernel's exp(-t k^2) with t = reach^2 / 4. The paper's 25
    // explicit iterations attenuate very differently.
    const double size = 48 * kRadius, wavelength = 12 * kRadius, amplitude = 0.2 * kRadius;
    double after[2], explicit_after[2];
    int k = 0;
    for (double edge : {0.27 * kRadius, 0.54 * kRadius}) {
        TriMesh m = wavy_plane(size, edge, wavelength, amplitude);
        TriMesh e = m;
        const MeshAdjacency adjacency = build_adjacency(m, 2);
        HeatSmoothingSettings s;
        s.reach = 4 * kRadius;
        s.particle_radius = kRadius;
        s.local_return = false;
        s.volume_correction = false;
        // Weights of 1 (not empty): an open sheet has no volume, so the guard against collapsed blobs must stay off.
        heat_smooth(m, adjacency, std::vector<float>(m.num_vertices(), 1.0f), s, 2);
        after[k] = sine_amplitude(m, size, wavelength) / amplitude;
        laplacian_smooth(e, adjacency, {}, 25, 1.0, 2);
        explicit_after[k] = sine_amplitude(e, size, wavelength) / amplitude;
        ++k;
    }
    INFO("heat " << after[0] << " / " << after[1] << ", explicit " << explicit_after[0] << " / " << explicit_after[1]);
    const double k2 = std::pow(2.0 * kPi / wavelength, 2.0), t = 4.0 * kRadius * kRadius;
    CHECK(after[0] == Approx(std::exp(-t * k2)).margin(0.05));
    CHECK(after[0] == Approx(after[1]).margin(0.03));
    CHECK(std::fabs(explicit_after[0] - explicit_after[1]) > 0.3);
}


TEST_CASE("heat smoothing: the part time sets how often the return runs, not what the flow does", "[heat]") {
    // Heat time 4 r^2: 4 parts of <= 1.25 r^2 (kPartTime), 2 of <= 2.5 r^2 (the part time before). exp(-t L) is the
    // product of its parts' filters, so without the return both give the same surface.
    const double size = 24 * kRadius;
    TriMesh base = wavy_plane(size, 0.54 * kRadius, 6 * kRadius, 0.2 * kRadius);
    const MeshAdjacency adjacency = build_adjacency(base, 2);
    std::vector<TriMesh> out;
    std::vector<int> parts;
    for (double part_time : {0.0, 2.5}) {
        TriMesh m = base;
        HeatSmoothingSettings s;
        s.reach = 4 * kRadius;
        s.particle_radius = kRadius;
        s.part_time = part_time;
        s.local_return = false;
        s.volume_correction = false;
        parts.push_back(heat_smooth(m, adjacency, std::vector<float>(m.num_vertices(), 1.0f), s, 2).parts);
        out.push_back(std::move(m));
    }
    CHECK(parts[0] == 4);
    CHECK(parts[1] == 2);
    {  // a part time that would split the flow into millions of parts is refused, naming it
        TriMesh m = base;
        HeatSmoothingSettings s;
        s.reach = 4 * kRadius;
        s.particle_radius = kRadius;
        s.part_time = 1e-9;
        CHECK_THROWS_WITH(heat_smooth(m, adjacency, {}, s, 2), Catch::Matchers::Contains("part_time"));
    }
    double largest = 0.0, moved = 0.0;
    for (std::size_t i = 0; i < base.vertices.size(); ++i) {
        largest = std::max(largest, std::fabs(double(out[0].vertices[i]) - out[1].vertices[i]));
        moved = std::max(moved, std::fabs(double(out[0].vertices[i]) - base.vertices[i]));
    }
    INFO("largest difference " << largest / kRadius << " r; largest move " << moved / kRadius << " r");
    CHECK(moved > 0.05 * kRadius);
    CHECK(largest < 0.01 * moved);
}
TEST_CASE("heat smoothing refuses what it cannot run and names it", "[heat]") {
    const TriMesh base = make_noisy_sphere(2, 1.0, 0.03);
    const MeshAdjacency adjacency = build_adjacency(base, 2);
    auto settings = [] {
        HeatSmoothingSettings s;
        s.reach = 0.4;
        s.particle_radius = 0.1;
        return s;
    };
    auto refusal = [&](const HeatSmoothingSettings& s, const MeshAdjacency& a) {
        TriMesh m = base;
        try {
            heat_smooth(m, a, {}, s, 2);
        } catch (const InputError& e) {
            CHECK(m.vertices == base.vertices);  // refused before anything moved
            return std::string(e.what());
        }
        return std::string("no error");
    };
    {  // a reach whose default parts would number in the tens of thousands (the pipeline's grows with the cube)
        HeatSmoothingSettings s = settings();
        s.reach = 40.0;
        CHECK_THAT(refusal(s, adjacency), Catch::Matchers::Contains("reach of 400 r") && Catch::Matchers::Contains("shorter smoothing reach"));
        s = settings();
        s.parts = 20000;
        CHECK_THAT(refusal(s, adjacency), Catch::Matchers::Contains("20000 parts"));
    }
    {  // a container wall that is not a number
        WallConstraints walls;
        walls.mask.assign(base.num_vertices(), 0);
        walls.mask[0] = 1u << 4;
        walls.planes = {-9, 9, -9, 9, std::nanf(""), 9};
        HeatSmoothingSettings s = settings();
        s.walls = &walls;
        CHECK_THAT(refusal(s, adjacency), Catch::Matchers::Contains("min z wall"));
    }
    {  // an adjacency without the triangles around each vertex (the returns' normals read them)
        MeshAdjacency neighbours_only;
        neighbours_only.vertex_neighbours = adjacency.vertex_neighbours;
        CHECK_THAT(refusal(settings(), neighbours_only), Catch::Matchers::Contains("heat_smooth"));
    }
    // A filter of more equivalent iterations than it runs (the coefficients alone cost O(N)).
    std::vector<float> x = base.vertices;
    CHECK_THROWS_WITH(heat_filter(x, 3, adjacency, {}, INFINITY, 1e-3, 2), Catch::Matchers::Contains("equivalent iterations"));
    CHECK_THROWS_AS(heat_coefficients(std::nan(""), 1e-3), InputError);
}

TEST_CASE("heat smoothing: the same physical surface at c = 0.25 and c = 0.5 (particles)", "[heat][slow]") {
    const std::vector<float> p = scene(false, false);
    double heat_abs[2], raw_abs[2], hfl_ratio[2], hfl_abs[2];
    int k = 0;
    for (double cube : {0.25, 0.5}) {
        const PipelineResult r = run(p, options(cube, 2));
        REQUIRE(check_mesh(r.mesh).ok());
        const MeshAdjacency a = build_adjacency(r.mesh, 2), ra = build_adjacency(r.raw_mesh, 2);
        heat_abs[k] = heat_distance(r.mesh, a, 2 * kRadius, 2) / kRadius;
        raw_abs[k] = heat_distance(r.raw_mesh, ra, 2 * kRadius, 2) / kRadius;
        // The hfL ratio: Taubin passes from the raw mesh's mean edge, the same for raw and smoothed.
        const MeshQuality raw = assess_quality(r.raw_mesh, 2, 2 * kRadius);
        hfl_abs[k] = assess_quality(r.mesh, 2, 2 * kRadius, raw.mean_edge_length).hfl / kRadius;
        hfl_ratio[k] = hfl_abs[k] * kRadius / raw.hfl;
        CHECK(r.stats.count("smoothing_reach", -1.0) == Approx(kMeasuredReach));  // the same at both cube sizes
        ++k;
    }
    INFO("smoothed " << heat_abs[0] << " / " << heat_abs[1] << " r, raw " << raw_abs[0] << " / " << raw_abs[1] << " r; hfL ratio "
                     << hfl_ratio[0] << " / " << hfl_ratio[1] << ", hfL " << hfl_abs[0] << " / " << hfl_abs[1] << " r");
    CHECK(heat_abs[0] < 0.5 * raw_abs[0]);
    CHECK(heat_abs[1] < 0.5 * raw_abs[1]);
    CHECK(heat_abs[0] == Approx(heat_abs[1]).epsilon(0.25));
    // No more particle-sized bumps left at the finer cubes, in absolute terms (the hfL, units of r). The
    // issue's ratio form (hfL / raw hfL) is not compared across cube sizes: the raw mesh at c = 0.5 carries the
    // coarser grid's own aliasing, so its denominator is about twice the one at c = 0.25 (0.086 r vs 0.039 r here)
    // while the smoothed surfaces have the same bumps (0.0046 r vs 0.0049 r): ratio 0.117 vs 0.057.
    CHECK(hfl_abs[0] <= hfl_abs[1]);
    CHECK(hfl_ratio[0] < 0.15);  // and the ratio target for surfaces without thin tubes
}

TEST_CASE("heat smoothing: weight-0 vertices keep their bits", "[heat]") {
    TriMesh mesh = make_noisy_sphere(3, 1.0, 0.03);
    const MeshAdjacency adjacency = build_adjacency(mesh, 2);
    std::vector<float> x = mesh.vertices;
    heat_filter(x, 3, adjacency, std::vector<float>(mesh.num_vertices(), 0.0f), 80.0, 1e-3, 2);
    CHECK(x == mesh.vertices);
    TriMesh smoothed = mesh;
    HeatSmoothingSettings s;
    s.reach = 0.5;
    s.particle_radius = 0.1;
    heat_smooth(smoothed, adjacency, std::vector<float>(mesh.num_vertices(), 0.0f), s, 2);
    CHECK(smoothed.vertices == mesh.vertices);
}

// A double cone over an n-gon: two apexes of valence n, ring vertices of valence 4.
TriMesh double_cone(int n) {
    TriMesh m;
    add_vertex(m, {0.0, 0.0, 1.0});
    add_vertex(m, {0.0, 0.0, -1.3});
    for (int k = 0; k < n; ++k) add_vertex(m, {std::cos(2.0 * kPi * k / n), (1.0 + 0.3 * (k % 3)) * std::sin(2.0 * kPi * k / n), 0.1 * (k % 2)});
    for (int k = 0; k < n; ++k) {
        const int32_t a = 2 + k, b = 2 + (k + 1) % n;
        add_triangle(m, 0, a, b);
        add_triangle(m, 1, b, a);
    }
    return m;
}

TEST_CASE("heat filter: rows longer than the fixed width count every neighbour (against a double-precision series)", "[heat]") {
    for (int n : {5, 8, 9, 13}) {  // apex rows shorter than, at, just over and well over the fixed width (8)
        const TriMesh mesh = double_cone(n);
        const MeshAdjacency adjacency = build_adjacency(mesh, 1);
        REQUIRE(adjacency.valence(0) == n);
        const int64_t nv = static_cast<int64_t>(mesh.num_vertices());
        std::vector<float> weights(static_cast<std::size_t>(nv));
        for (int64_t i = 0; i < nv; ++i) weights[i] = 0.4f + 0.05f * static_cast<float>(i % 7);
        const double iterations = 6.0;
        const std::vector<double> c = heat_coefficients(iterations, 1e-6);
        for (int dims : {1, 3}) {
            std::vector<double> start(static_cast<std::size_t>(dims * nv));
            for (int64_t i = 0; i < nv; ++i)
                for (int d = 0; d < dims; ++d) start[dims * i + d] = dims == 3 ? mesh.vertices[3 * i + d] : std::sin(1.7 * i);
            // exp(N (Y - I)) x as the series sum c_k T_k(Y) x, Y = I + w (mean - I), in double over the CSR rows.
            auto apply = [&](const std::vector<double>& t) {
                std::vector<double> y(t.size());
                for (int64_t i = 0; i < nv; ++i)
                    for (int d = 0; d < dims; ++d) {
                        double sum = 0.0;
                        for (int64_t k = adjacency.vertex_neighbours.begin(i); k < adjacency.vertex_neighbours.end(i); ++k)
                            sum += t[dims * adjacency.vertex_neighbours.items[k] + d] - t[dims * i + d];
                        y[dims * i + d] = t[dims * i + d] + weights[i] * sum / adjacency.valence(i);
                    }
                return y;
            };
            std::vector<double> older = start, current = apply(start), expected(start.size());
            for (std::size_t e = 0; e < start.size(); ++e) expected[e] = c[0] * older[e] + c[1] * current[e];
            for (std::size_t k = 2; k < c.size(); ++k) {
                std::vector<double> next = apply(current);
                for (std::size_t e = 0; e < start.size(); ++e) next[e] = 2.0 * next[e] - older[e], expected[e] += c[k] * next[e];
                older.swap(current), current.swap(next);
            }
            std::vector<float> x(start.begin(), start.end());
            heat_filter(x, dims, adjacency, weights, iterations, 1e-6, 2);
            double moved = 0.0;
            for (std::size_t e = 0; e < start.size(); ++e) {
                CHECK(std::fabs(x[e] - expected[e]) < 2e-6);
                moved = std::max(moved, std::fabs(expected[e] - start[e]));
            }
            CHECK(moved > 0.05);  // the filter did smooth: the comparison is not between two unmoved copies
        }
    }
}

TEST_CASE("heat smoothing: pool smoothed, tube keeps its volume where it is, droplet untouched", "[heat][slow]") {
    const std::vector<float> p = scene(true, true);
    for (double cube : {1.0, 0.5}) {
        INFO("cube " << cube);
        PipelineOptions o = options(cube, 2);
        o.postprocess.volume_restoration = false;  // the local return alone: no per-component offset
        const PipelineResult r = run(p, o);
        REQUIRE(check_mesh(r.mesh).ok());
        const auto before = sorted_volumes(r.raw_mesh), after = sorted_volumes(r.mesh);
        REQUIRE(before.size() == 3);  // droplet, tube, pool
        REQUIRE(after.size() == 3);
        PipelineOptions unsmoothed = options(cube, 2);
        unsmoothed.postprocess.smoothing_iterations = 0;
        const auto decimated = sorted_volumes(run(p, unsmoothed).mesh);
        CHECK(after[0] == Approx(decimated[0]).epsilon(1e-6));  // the droplet (weight 0) is not moved
        CHECK(after[1] / before[1] > 0.97);                     // the tube: held locally
        CHECK(after[1] / before[1] < 1.03);                     // and not inflated
        // The pool: the volume targets (2 % at c = 1.0, 1 % at c <= 0.5) before any per-component offset.
        CHECK(after[2] / before[2] == Approx(1.0).epsilon(cube > 0.5 ? 0.02 : 0.01));
        CHECK(assess_quality(r.mesh).bumpiness < 0.5 * assess_quality(r.raw_mesh).bumpiness);
        // With the final correction every component's volume is exact.
        const PipelineResult corrected = run(p, options(cube, 2));
        const auto exact = sorted_volumes(corrected.mesh);
        CHECK(exact[1] == Approx(decimated[1]).epsilon(1e-4));
        CHECK(exact[2] == Approx(decimated[2]).epsilon(1e-4));
        // Locally too: the middle third of the tube keeps its volume to within 3 % at c = 0.5 and 9 % at c = 1.0
        // (measured: 1.027 / 1.084 from the flow, 1.021 / 1.086 after the correction, the return low-passed on
        // aggregates; on the mesh: 1.020 / 1.013 at c = 0.5, 1.069 / 1.070 at c = 1.0, where it cost three times as
        // much; the paper's 25 iterations with per-component restoration: 1.019 / 1.111). The tube is 40 r long and the
        // local return averages over 9 r, so part of what its caps lose comes back in its middle: at c = 1.0 this misses
        // the 2 %.
        const double raw_section = tube_section_volume(r.raw_mesh), bound = cube > 0.5 ? 0.09 : 0.03;
        CHECK(tube_section_volume(r.mesh) / raw_section == Approx(1.0).epsilon(bound));
        CHECK(tube_section_volume(corrected.mesh) / raw_section == Approx(1.0).epsilon(bound));
    }
}

TEST_CASE("heat smoothing: vertices on a wall stay on it and slide along it", "[heat]") {
    // A noisy sphere whose bottom cap is pressed onto the wall z = -0.6 (min z): those vertices are on the wall.
    TriMesh mesh = make_noisy_sphere(4, 1.0, 0.04);
    WallConstraints walls;
    walls.mask.assign(mesh.num_vertices(), 0);
    walls.planes = {-9, 9, -9, 9, -0.6f, 9};
    std::size_t on_wall = 0;
    for (std::size_t v = 0; v < mesh.num_vertices(); ++v)
        if (mesh.vertices[3 * v + 2] < -0.6f) {
            mesh.vertices[3 * v + 2] = -0.6f;
            walls.mask[v] = 1u << 4;
            ++on_wall;
        }
    REQUIRE(on_wall > 20);
    const TriMesh start = mesh;
    const MeshAdjacency adjacency = build_adjacency(mesh, 2);
    HeatSmoothingSettings s;
    s.reach = 0.4;
    s.particle_radius = 0.1;
    s.walls = &walls;
    heat_smooth(mesh, adjacency, {}, s, 2);
    double slid = 0.0;
    for (std::size_t v = 0; v < mesh.num_vertices(); ++v) {
        if (!walls.mask[v]) continue;
        CHECK(mesh.vertices[3 * v + 2] == -0.6f);
        slid = std::max(slid, std::hypot(double(mesh.vertices[3 * v]) - start.vertices[3 * v],
                                         double(mesh.vertices[3 * v + 1]) - start.vertices[3 * v + 1]));
    }
    CHECK(slid > 1e-3);  // they moved along the wall
    CHECK(assess_quality(mesh).volume == Approx(assess_quality(start).volume).epsilon(1e-4));
    // Without walls the same vertices leave the plane.
    TriMesh free = start;
    s.walls = nullptr;
    heat_smooth(free, adjacency, {}, s, 2);
    std::size_t off = 0;
    for (std::size_t v = 0; v < free.num_vertices(); ++v) off += walls.mask[v] && free.vertices[3 * v + 2] != -0.6f;
    CHECK(off > 0);
}

TEST_CASE("heat smoothing is the same for any thread count", "[heat][slow]") {
    const std::vector<float> p = scene(true, true);
    const PipelineResult one = run(p, options(0.75, 1));
    const PipelineResult two = run(p, options(0.75, 2));
    const PipelineResult three = run(p, options(0.75, 3));
    CHECK(one.mesh.vertices == two.mesh.vertices);
    CHECK(one.mesh.vertices == three.mesh.vertices);
    CHECK(one.mesh.normals == two.mesh.normals);
    CHECK(one.mesh.normals == three.mesh.normals);
    TriMesh mesh = make_noisy_sphere(4, 1.0, 0.05);
    const MeshAdjacency adjacency = build_adjacency(mesh, 1);
    HeatSmoothingSettings s;
    s.reach = 0.3;
    s.particle_radius = 0.1;
    TriMesh a = mesh, b = mesh;
    heat_smooth(a, adjacency, {}, s, 1);
    heat_smooth(b, adjacency, {}, s, 3);
    CHECK(a.vertices == b.vertices);
}

TEST_CASE("hfL: Taubin passes from the raw mesh's edge, heat variant, in the quality report", "[heat]") {
    CHECK(hfl_passes(2.0, 1.0) == 5);  // round(1.36 * 4)
    CHECK(hfl_passes(0.05, 0.0135) == static_cast<int>(std::lround(1.36 * std::pow(0.05 / 0.0135, 2.0))));
    const TriMesh noisy = make_noisy_sphere(4, 1.0, 0.05), smooth = make_icosphere(4, 1.0);
    const MeshQuality q = assess_quality(noisy, 2, 0.2);
    CHECK(q.mean_edge_length > 0.0);
    CHECK(q.hfl_passes == hfl_passes(0.2, q.mean_edge_length));
    CHECK(q.hfl > 0.0);
    CHECK(q.heat_bumpiness > 0.0);
    const MeshQuality s = assess_quality(smooth, 2, 0.2, q.mean_edge_length);
    CHECK(s.hfl_passes == q.hfl_passes);
    CHECK(s.hfl < 0.5 * q.hfl);
    CHECK(s.heat_bumpiness < 0.5 * q.heat_bumpiness);
    CHECK(assess_quality(noisy, 2).hfl_passes == 0);  // no scale: not measured
}

TEST_CASE("heat filter: explicit steps, where shorter than the series, smooth as the heat kernel does", "[heat]") {
    const double n = 3.4;  // the series needs more terms than ceil(N) = 4 steps
    REQUIRE(heat_coefficients(n, 1e-3).size() - 1 > 4);
    // A smooth field: z on a sphere (a low-frequency eigenfunction of the umbrella operator).
    const TriMesh sphere = make_icosphere(4);
    const MeshAdjacency adjacency = build_adjacency(sphere, 2);
    const int64_t nv = static_cast<int64_t>(sphere.num_vertices());
    std::vector<float> start(static_cast<std::size_t>(nv));
    for (int64_t i = 0; i < nv; ++i) start[i] = sphere.vertices[3 * i + 2];
    std::vector<float> series = start, steps = start;
    CHECK(heat_filter(series, 1, adjacency, {}, n, 1e-3, 2) == static_cast<int>(heat_coefficients(n, 1e-3).size()) - 1);
    CHECK(heat_filter(steps, 1, adjacency, {}, n, 1e-3, 2, nullptr, true) == 4);
    double smoothed = 0.0, apart = 0.0;  // sums of squares: how far the series moved the field, how far apart the two end
    for (int64_t i = 0; i < nv; ++i) {
        smoothed += (double(series[i]) - start[i]) * (double(series[i]) - start[i]);
        apart += (double(steps[i]) - series[i]) * (double(steps[i]) - series[i]);
    }
    INFO("RMS moved " << std::sqrt(smoothed / nv) << ", apart " << std::sqrt(apart / nv));
    CHECK(std::sqrt(smoothed / nv) > 1e-3);         // the field did move
    CHECK(std::sqrt(apart / smoothed) < 0.05);      // and both moved it alike
    // Noise (the particles' bumps): both take most of it out.
    const TriMesh noisy = make_noisy_sphere(4, 1.0, 0.03);
    const MeshAdjacency noisy_adjacency = build_adjacency(noisy, 2);
    auto roughness = [&](const std::vector<float>& x) {  // RMS of the radius about its mean
        double sum = 0.0, sum2 = 0.0;
        const int64_t count = static_cast<int64_t>(x.size() / 3);
        for (int64_t i = 0; i < count; ++i) {
            const double r = std::sqrt(double(x[3 * i]) * x[3 * i] + double(x[3 * i + 1]) * x[3 * i + 1] + double(x[3 * i + 2]) * x[3 * i + 2]);
            sum += r, sum2 += r * r;
        }
        return std::sqrt(std::max(0.0, sum2 / count - (sum / count) * (sum / count)));
    };
    std::vector<float> series3 = noisy.vertices, steps3 = noisy.vertices;
    heat_filter(series3, 3, noisy_adjacency, {}, n, 1e-3, 2);
    heat_filter(steps3, 3, noisy_adjacency, {}, n, 1e-3, 2, nullptr, true);
    const double before = roughness(noisy.vertices);
    CHECK(roughness(series3) < 0.5 * before);
    CHECK(roughness(steps3) < 0.5 * before);
    CHECK(roughness(steps3) < 1.5 * roughness(series3));
}
