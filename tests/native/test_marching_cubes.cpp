// Marching cubes (surface/marching_cubes.h, surface/bricks.h): the generated case table and whole meshes of
// analytic and random fields, closed, manifold and oriented.
#include <catch2/catch.hpp>

#include <cmath>
#include <random>
#include <vector>

#include "base/numbers.h"
#include "mesh/topology.h"
#include "mesh_builders.h"
#include "surface/bricks.h"
#include "surface/marching_cubes.h"

using namespace meniscus;
using namespace meniscus::test;

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
