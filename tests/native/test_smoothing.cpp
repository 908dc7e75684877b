// Weighted Laplacian smoothing (post/smoothing.h, Eq. 3-5).
#include <catch2/catch.hpp>

#include <vector>

#include "analysis/quality.h"
#include "base/errors.h"
#include "mesh_builders.h"
#include "post/smoothing.h"

using namespace meniscus;
using namespace meniscus::test;

TEST_CASE("Laplacian smoothing removes noise", "[smoothing]") {
    TriMesh m = make_noisy_sphere(4, 1.0, 0.03, 7);
    const double before = assess_quality(m).bumpiness;
    laplacian_smooth(m, {}, 10, 0.5, 2);
    const MeshQuality after = assess_quality(m);
    CHECK(after.bumpiness < 0.5 * before);
    CHECK(after.check.ok());
    CHECK(all_finite(m.vertices));
}

TEST_CASE("Laplacian smoothing keeps zero-weight vertices in place", "[smoothing]") {
    TriMesh m = make_noisy_sphere(3, 1.0, 0.05, 3);
    const TriMesh original = m;
    std::vector<float> weights(m.num_vertices(), 1.0f);
    weights[17] = 0.0f;
    weights[100] = 0.0f;
    laplacian_smooth(m, weights, 25, 1.0, 2);
    for (int v : {17, 100})
        for (int k = 0; k < 3; ++k) CHECK(m.vertices[3 * v + k] == original.vertices[3 * v + k]);
    CHECK(m.vertices[3 * 18] != original.vertices[3 * 18]);
}

TEST_CASE("Laplacian smoothing is bit-identical for 1 and 2 threads", "[smoothing]") {
    TriMesh a = make_noisy_sphere(4, 1.0, 0.03, 11);
    TriMesh b = a;
    std::vector<float> weights(a.num_vertices());
    for (std::size_t i = 0; i < weights.size(); ++i) weights[i] = static_cast<float>((i * 37) % 101) / 100.0f;
    laplacian_smooth(a, weights, 20, 0.8, 1);
    laplacian_smooth(b, weights, 20, 0.8, 2);
    CHECK(a.vertices == b.vertices);
}

TEST_CASE("Laplacian smoothing refuses out-of-range indices and a wrong weight count", "[smoothing]") {
    TriMesh m = make_cube();
    m.triangles[5] = 42;
    CHECK_THROWS_AS(laplacian_smooth(m, {}, 1, 0.5, 1), InputError);
    TriMesh n = make_cube();
    CHECK_THROWS_AS(laplacian_smooth(n, std::vector<float>(3, 1.0f), 1, 0.5, 1), InputError);
}
