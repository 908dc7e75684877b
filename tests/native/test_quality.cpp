// The quality report (analysis/quality.h): volume, area, components, bumpiness, normal angles, valences.
#include <catch2/catch.hpp>

#include <cstddef>

#include "analysis/quality.h"
#include "base/numbers.h"
#include "mesh_builders.h"

using namespace meniscus;
using namespace meniscus::test;

TEST_CASE("icosphere volume and area approach the sphere's", "[quality]") {
    const double r = 2.0;
    // An inscribed polyhedron: its volume is below the sphere's by O(edge^2); at level 5 (edge ~ 0.034 r) the
    // difference is about 0.1 %.
    for (V3 centre : {V3{0, 0, 0}, V3{1000, -2000, 500}}) {
        const MeshQuality q = assess_quality(make_icosphere(5, r, centre), 2);
        const double sphere = 4.0 / 3.0 * kPi * r * r * r;
        CHECK(q.check.ok());
        CHECK(q.volume < sphere);
        CHECK(q.volume == Approx(sphere).epsilon(3e-3));
        CHECK(q.area == Approx(4 * kPi * r * r).epsilon(3e-3));
        REQUIRE(q.components.size() == 1);
        CHECK(q.components[0].volume == Approx(q.volume).epsilon(1e-9));
        CHECK(q.components[0].triangles == q.triangles);
    }
}

TEST_CASE("components are found and sorted by signed volume", "[quality]") {
    SECTION("two spheres") {
        TriMesh m = make_icosphere(3, 1.0, {5, 0, 0});
        append(m, make_icosphere(3, 2.0, {-5, 0, 0}));
        const MeshQuality q = assess_quality(m);
        REQUIRE(q.components.size() == 2);
        CHECK(q.components[0].volume == Approx(4.0 / 3.0 * kPi * 8).epsilon(0.02));
        CHECK(q.components[1].volume == Approx(4.0 / 3.0 * kPi).epsilon(0.02));
        CHECK(q.components[0].triangles == q.components[1].triangles);
        CHECK(q.volume == Approx(q.components[0].volume + q.components[1].volume));
    }
    SECTION("a bubble: sphere inside a sphere, inner one inverted") {
        TriMesh m = make_icosphere(3, 2.0);
        TriMesh bubble = make_icosphere(3, 1.0);
        flip_orientation(bubble);
        append(m, bubble);
        const MeshQuality q = assess_quality(m);
        CHECK(q.check.ok());
        REQUIRE(q.components.size() == 2);
        CHECK(q.components[0].volume > 0);
        CHECK(q.components[1].volume < 0);
        CHECK(q.components[1].volume == Approx(-4.0 / 3.0 * kPi).epsilon(0.02));
        CHECK(q.volume == Approx(4.0 / 3.0 * kPi * 7).epsilon(0.02));
    }
}

TEST_CASE("quality report: valences, normal angles, bumpiness", "[quality]") {
    const MeshQuality smooth = assess_quality(make_icosphere(4));
    const MeshQuality noisy = assess_quality(make_noisy_sphere(4, 1.0, 0.05));
    std::size_t total = 0;
    for (std::size_t n : smooth.valence_histogram) total += n;
    CHECK(total == smooth.vertices);
    REQUIRE(smooth.valence_histogram.size() == 7);
    CHECK(smooth.valence_histogram[5] == 12);
    CHECK(smooth.mean_normal_angle_deg > 0.5);
    CHECK(smooth.mean_normal_angle_deg < 5.0);
    CHECK(noisy.mean_normal_angle_deg > 2 * smooth.mean_normal_angle_deg);
    // The low-pass copy of a coarse sphere differs from it a little too (Taubin's pass band amplifies the lowest
    // frequencies slightly): bumpiness is a comparison between meshes, not an absolute noise level.
    CHECK(noisy.bumpiness > 2 * smooth.bumpiness);
    CHECK(smooth.single_vertex_configurations == 0);
    CHECK(smooth.double_vertex_configurations == 0);
    // Deterministic for any thread count.
    const MeshQuality one = assess_quality(make_noisy_sphere(4, 1.0, 0.05), 1);
    CHECK(one.volume == noisy.volume);
    CHECK(one.bumpiness == noisy.bumpiness);
    CHECK(one.mean_normal_angle_deg == noisy.mean_normal_angle_deg);
}
