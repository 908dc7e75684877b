// Vertex normals (post/normals.h, Sec. 3.4): area-weighted, smoothed by Eq. 12, and the normals stage's choice.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <vector>

#include "mesh/adjacency.h"
#include "mesh_builders.h"
#include "post/normals.h"
#include "post/smoothing.h"
#include "post/volume.h"

using namespace meniscus;
using namespace meniscus::test;

TEST_CASE("area-weighted normals of a sphere point outward", "[normals]") {
    TriMesh m = make_icosphere(4, 3.0);
    compute_area_weighted_normals(m, 2);
    REQUIRE(m.normals.size() == m.vertices.size());
    for (std::size_t v = 0; v < m.num_vertices(); ++v) {
        const V3 p = vertex_of(m, static_cast<int32_t>(v));
        const double r = std::sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]);
        const double d = (m.normals[3 * v] * p[0] + m.normals[3 * v + 1] * p[1] + m.normals[3 * v + 2] * p[2]) / r;
        CHECK(d > 0.99);
    }
    smooth_normals(m, 10, 2);
    double worst = 0.0, worst_dot = 1.0;
    for (std::size_t v = 0; v < m.num_vertices(); ++v) {
        const float* n = m.normals.data() + 3 * v;
        worst = std::max(worst, std::fabs(std::sqrt(double(n[0]) * n[0] + double(n[1]) * n[1] + double(n[2]) * n[2]) - 1.0));
        const V3 p = vertex_of(m, static_cast<int32_t>(v));
        const double r = std::sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]);
        worst_dot = std::min(worst_dot, (n[0] * p[0] + n[1] * p[1] + n[2] * p[2]) / r);
    }
    CHECK(worst < 1e-5);
    CHECK(worst_dot > 0.99);
}

TEST_CASE("normals never become NaN", "[normals]") {
    TriMesh m = make_cube();
    add_vertex(m, {9, 9, 9});  // unreferenced
    // A zero-area triangle whose vertices have no other triangle.
    const int32_t p = add_vertex(m, {3, 3, 3}), q = add_vertex(m, {3, 3, 3}), r = add_vertex(m, {4, 4, 4});
    add_triangle(m, p, q, r);
    compute_area_weighted_normals(m, 1);
    CHECK(all_finite(m.normals));
    smooth_normals(m, 5, 1);
    CHECK(all_finite(m.normals));
    for (std::size_t v = 0; v < m.num_vertices(); ++v) {
        const float* n = m.normals.data() + 3 * v;
        CHECK(std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]) == Approx(1.0).epsilon(1e-5));
    }
}

TEST_CASE("normal smoothing is bit-identical for 1 and 2 threads", "[normals]") {
    TriMesh a = make_noisy_sphere(4, 1.0, 0.03, 5);
    compute_area_weighted_normals(a, 1);
    TriMesh b = a;
    smooth_normals(a, 7, 1);
    smooth_normals(b, 7, 2);
    CHECK(a.normals == b.normals);
}

TEST_CASE("the normals stage takes restoration's normals only when they are the ones asked for", "[normals]") {
    TriMesh m = make_noisy_sphere(4, 1.0, 0.03, 9);
    const UnsmoothedSurface unsmoothed = record_unsmoothed_surface(m, 2);
    laplacian_smooth(m, {}, 10, 1.0, 2);
    const MeshAdjacency adjacency = build_adjacency(m, 2);
    const SmoothedNormals along = restore_component_volumes(m, adjacency, unsmoothed, {}, 0.5, 10, 2);
    REQUIRE(along.iterations == 10);
    REQUIRE(along.values.size() == m.vertices.size());
    CHECK(smoothed_vertex_normals(m, adjacency, 10, along, 2) == along.values);
    // Another iteration count: computed anew, as they would be without restoration.
    std::vector<float> fresh = area_weighted_normals(m, adjacency.vertex_triangles, 2);
    smooth_normals(fresh, adjacency.vertex_neighbours, 3, 2);
    CHECK(smoothed_vertex_normals(m, adjacency, 3, along, 2) == fresh);
    CHECK(smoothed_vertex_normals(m, adjacency, 3, SmoothedNormals{}, 1) == fresh);
}
