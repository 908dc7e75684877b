// Surface aggregates (post/surface_aggregates.h): the coarse graph the physical-reach smoothing's local return runs on.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <vector>

#include "base/disjoint_sets.h"
#include "mesh/adjacency.h"
#include "mesh/components.h"
#include "mesh_builders.h"
#include "post/heat_smoothing.h"
#include "post/surface_aggregates.h"

using namespace meniscus;
using namespace meniscus::test;

namespace {

// Two spheres 0.05 apart: cells of 0.5 hold pieces of both near where they almost touch.
TriMesh two_close_spheres() {
    TriMesh m = make_icosphere(4, 1.0, {0, 0, 0});
    append(m, make_icosphere(4, 1.0, {2.05, 0, 0}));
    return m;
}

}  // namespace

TEST_CASE("surface aggregates: edge-connected pieces of one cell, symmetric coupling", "[aggregates]") {
    const TriMesh m = two_close_spheres();
    const MeshAdjacency adjacency = build_adjacency(m, 2);
    const double cell = 0.5;
    const SurfaceAggregates g = aggregate_surface(m, adjacency, cell, 2);
    REQUIRE(g.size() > 20);
    REQUIRE(g.size() < m.num_vertices() / 4);
    int32_t components = 0;
    const std::vector<int32_t> component = component_labels(m, &components);
    REQUIRE(components == 2);
    double lo[3] = {1e9, 1e9, 1e9};
    for (std::size_t i = 0; i < m.num_vertices(); ++i)
        for (int k = 0; k < 3; ++k) lo[k] = std::min(lo[k], double(m.vertices[3 * i + k]));
    std::size_t members = 0;
    for (std::size_t a = 0; a < g.size(); ++a) {
        REQUIRE(g.members.size(a) > 0);
        members += static_cast<std::size_t>(g.members.size(a));
        // One cell, one sphere, and connected by the mesh's edges inside the aggregate.
        const int32_t first = g.members.items[g.members.begin(a)];
        DisjointSets inside(m.num_vertices());
        for (int64_t k = g.members.begin(a); k < g.members.end(a); ++k) {
            const int32_t v = g.members.items[k];
            CHECK(g.of_vertex[v] == static_cast<int32_t>(a));
            CHECK(component[v] == component[first]);
            for (int d = 0; d < 3; ++d)
                CHECK(std::floor((m.vertices[3 * v + d] - lo[d]) / cell) == std::floor((m.vertices[3 * first + d] - lo[d]) / cell));
            for (int64_t e = adjacency.vertex_neighbours.begin(v); e < adjacency.vertex_neighbours.end(v); ++e)
                if (g.of_vertex[adjacency.vertex_neighbours.items[e]] == static_cast<int32_t>(a)) inside.unite(v, adjacency.vertex_neighbours.items[e]);
        }
        for (int64_t k = g.members.begin(a); k < g.members.end(a); ++k) CHECK(inside.find(g.members.items[k]) == inside.find(first));
        // Coupled both ways with the same number of edges, never across the gap between the spheres.
        for (int64_t k = g.neighbours.begin(a); k < g.neighbours.end(a); ++k) {
            const int32_t b = g.neighbours.items[k];
            CHECK(b != static_cast<int32_t>(a));
            CHECK(component[g.members.items[g.members.begin(b)]] == component[first]);
            const int32_t* row = g.neighbours.row(b);
            const int32_t* found = std::lower_bound(row, row + g.neighbours.size(b), static_cast<int32_t>(a));
            REQUIRE(found != row + g.neighbours.size(b));
            REQUIRE(*found == static_cast<int32_t>(a));
            CHECK(g.coupling[g.neighbours.begin(b) + (found - row)] == g.coupling[k]);
        }
    }
    CHECK(members == m.num_vertices());
}

TEST_CASE("surface aggregates: restriction keeps constants, the coarse heat filter keeps constants and its bits", "[aggregates]") {
    const TriMesh m = make_noisy_sphere(4, 1.0, 0.03);
    const MeshAdjacency adjacency = build_adjacency(m, 2);
    std::vector<float> areas(m.num_vertices());
    for (std::size_t i = 0; i < areas.size(); ++i) areas[i] = 0.5f + 0.001f * static_cast<float>(i % 7);
    const SurfaceAggregates g = aggregate_surface(m, adjacency, 0.3, 2);
    const std::vector<float> constant(m.num_vertices(), 2.5f);
    for (double v : restrict_to_aggregates(g, areas, constant.data(), 1, 2)) CHECK(v == Approx(2.5).epsilon(1e-12));
    const std::vector<double> centre = restrict_to_aggregates(g, areas, m.vertices.data(), 3, 2);
    CHECK(rms_coupled_distance(g, centre, 2) > 0.1);
    CHECK(rms_coupled_distance(g, centre, 2) < 0.6);

    std::vector<double> ones(g.size(), 1.0);
    aggregate_chebyshev(ones, 1, g, {}, heat_coefficients(50.0, 1e-3), 2);
    for (double v : ones) CHECK(v == Approx(1.0).epsilon(1e-9));

    // A spike spreads out and keeps sum(degree x), degree the total coupling (the coupling-weighted mean is a random
    // walk whose stationary weights are the degrees).
    std::vector<double> degree(g.size(), 0.0);
    for (std::size_t a = 0; a < g.size(); ++a)
        for (int64_t k = g.neighbours.begin(a); k < g.neighbours.end(a); ++k) degree[a] += g.coupling[k];
    std::vector<double> spread(g.size(), 0.0);
    spread[0] = 1.0;
    aggregate_chebyshev(spread, 1, g, {}, heat_coefficients(20.0, 1e-3), 2);
    double kept = 0.0;
    for (std::size_t a = 0; a < g.size(); ++a) kept += degree[a] * spread[a];
    CHECK(kept == Approx(degree[0]).epsilon(1e-9));
    CHECK(spread[0] < 0.1);
    // The bits do not depend on the threads; an aggregate of weight 0 keeps its value.
    std::vector<double> weights(g.size(), 1.0);
    weights[g.size() / 2] = 0.0;
    std::vector<std::vector<double>> results;
    for (int threads : {1, 2, 3}) {
        std::vector<double> spike(g.size(), 0.0);
        spike[0] = 1.0;
        spike[g.size() / 2] = 0.25;
        aggregate_chebyshev(spike, 1, g, weights, heat_coefficients(20.0, 1e-3), threads);
        results.push_back(spike);
    }
    CHECK(results[0] == results[1]);
    CHECK(results[0] == results[2]);
    CHECK(results[0][0] < 0.1);
    CHECK(results[0][g.size() / 2] == 0.25);
}

TEST_CASE("heat smoothing: the return's low-pass on aggregates matches the mesh's", "[aggregates][heat]") {
    // A noisy sphere (radius 12 r, edge ~0.4 r): the flow with the return low-passed on the mesh and on aggregates
    // gives the same surface to a small fraction of the particle radius, with fewer operator applications.
    const double r = 0.05;
    const TriMesh noisy = make_noisy_sphere(5, 12 * r, 0.3 * r);
    const MeshAdjacency adjacency = build_adjacency(noisy, 2);
    HeatSmoothingSettings s;
    s.reach = 4.28 * r;
    s.particle_radius = r;
    TriMesh on_mesh = noisy, on_aggregates = noisy;
    s.aggregate_size = 0.0;
    const HeatSmoothingReport mesh_report = heat_smooth(on_mesh, adjacency, {}, s, 2);
    s.aggregate_size = -1.0;  // kAggregateCell
    const HeatSmoothingReport coarse_report = heat_smooth(on_aggregates, adjacency, {}, s, 2);
    CHECK(coarse_report.aggregates > 100);
    CHECK(coarse_report.applications < mesh_report.applications);
    double largest = 0.0, moved = 0.0;
    for (std::size_t i = 0; i < noisy.vertices.size(); ++i) {
        largest = std::max(largest, double(std::fabs(on_mesh.vertices[i] - on_aggregates.vertices[i])));
        moved = std::max(moved, double(std::fabs(on_mesh.vertices[i] - noisy.vertices[i])));
    }
    INFO("largest difference " << largest / r << " r; largest move " << moved / r << " r");
    CHECK(moved > 0.2 * r);
    CHECK(largest < 0.02 * r);
    // The same bits on any number of threads.
    TriMesh again = noisy;
    heat_smooth(again, adjacency, {}, s, 3);
    CHECK(again.vertices == on_aggregates.vertices);
}

TEST_CASE("surface aggregates: empty meshes, lone vertices, zero weights and scenes too wide for the keys", "[aggregates]") {
    TriMesh empty;
    CHECK(aggregate_surface(empty, build_adjacency(empty, 2), 0.5, 2).size() == 0);

    // Lone vertices (in no triangle) are aggregates of their own, coupled to nothing; zero weights give plain means.
    TriMesh m = make_noisy_sphere(4, 1.0, 0.03);  // edges ~0.066: cells of 1.5 r = 0.15 at r = 0.1
    add_vertex(m, {5.0, 5.0, 5.0});
    add_vertex(m, {5.1, 5.0, 5.0});
    const MeshAdjacency adjacency = build_adjacency(m, 2);
    const SurfaceAggregates g = aggregate_surface(m, adjacency, 0.5, 2);
    const int32_t lone = g.of_vertex[m.num_vertices() - 1];
    CHECK(g.members.size(lone) == 1);
    CHECK(g.neighbours.size(lone) == 0);
    CHECK(g.of_vertex[m.num_vertices() - 2] != lone);
    const std::vector<float> zero(m.num_vertices(), 0.0f), ones(m.num_vertices(), 1.0f);
    const std::vector<double> by_zero = restrict_to_aggregates(g, zero, m.vertices.data(), 3, 2);
    const std::vector<double> by_ones = restrict_to_aggregates(g, ones, m.vertices.data(), 3, 2);
    CHECK(by_zero == by_ones);
    CHECK_THROWS_AS(restrict_to_aggregates(g, zero, m.vertices.data(), 4, 2), InputError);
    CHECK_THROWS_AS(restrict_to_aggregates(g, std::vector<float>(3, 1.0f), m.vertices.data(), 3, 2), InputError);
    HeatSmoothingSettings s;
    s.reach = 0.5;
    s.particle_radius = 0.1;
    TriMesh smoothed = m;
    const HeatSmoothingReport report = heat_smooth(smoothed, adjacency, {}, s, 2);
    CHECK(report.aggregates > 0);
    for (float x : smoothed.vertices) REQUIRE(std::isfinite(x));
    CHECK(smoothed.vertices[3 * (m.num_vertices() - 1)] == 5.1f);  // nothing to average with: not moved

    // Two pieces 1e6 cells of 0.15 apart fit the keys' 21 bits, 2.7e6 do not: then no aggregates, and the smoothing
    // low-passes on the mesh.
    for (double offset : {1.5e5, 4.0e5}) {
        INFO("offset " << offset);
        TriMesh wide = make_noisy_sphere(4, 1.0, 0.03);
        TriMesh far = wide;
        for (std::size_t i = 0; i < far.num_vertices(); ++i) far.vertices[3 * i] = static_cast<float>(far.vertices[3 * i] + offset);
        append(wide, far);
        const MeshAdjacency wide_adjacency = build_adjacency(wide, 2);
        const bool fits = offset < 2.0e5;
        CHECK((aggregate_surface(wide, wide_adjacency, 0.15, 2).size() > 0) == fits);
        TriMesh wide_smoothed = wide;
        const HeatSmoothingReport wide_report = heat_smooth(wide_smoothed, wide_adjacency, {}, s, 2);
        CHECK((wide_report.aggregates > 0) == fits);
        CHECK(wide_report.applications > 0);
        for (float x : wide_smoothed.vertices) REQUIRE(std::isfinite(x));
    }
}
