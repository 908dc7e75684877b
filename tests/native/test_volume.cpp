// Connected components and their volumes (mesh/components.h), volume restoration and the collapse guard
// (post/volume.h).
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <vector>

#include "base/numbers.h"
#include "mesh/adjacency.h"
#include "mesh/components.h"
#include "mesh/topology.h"
#include "mesh_builders.h"
#include "post/smoothing.h"
#include "post/volume.h"

using namespace meniscus;
using namespace meniscus::test;

TEST_CASE("components are labelled and their volumes measured", "[volume]") {
    TriMesh mesh = make_icosphere(3, 1.0);
    append(mesh, make_icosphere(3, 0.5, {5, 0, 0}));
    int32_t count = 0;
    const auto labels = component_labels(mesh, &count);
    REQUIRE(count == 2);
    const auto volumes = component_volumes(mesh, labels, count);
    CHECK(volumes[0] == Approx(4.0 / 3.0 * kPi).epsilon(0.02));
    CHECK(volumes[1] == Approx(4.0 / 3.0 * kPi / 8.0).epsilon(0.02));
}

TEST_CASE("restoration gives each smoothed component its volume back, weighted vertices only", "[volume]") {
    TriMesh mesh = make_noisy_sphere(4, 1.0, 0.03);
    append(mesh, make_icosphere(3, 0.3, {4, 0, 0}));
    const UnsmoothedSurface unsmoothed = record_unsmoothed_surface(mesh, 2);
    const std::vector<int32_t>& labels = unsmoothed.labels;
    const int32_t count = unsmoothed.components;
    const std::vector<double>& target = unsmoothed.volumes;
    // The big sphere is smoothed (weight 1), the small one is a "droplet" (weight 0).
    std::vector<float> weights(mesh.num_vertices());
    for (std::size_t v = 0; v < weights.size(); ++v) weights[v] = labels[v] == 0 ? 1.0f : 0.0f;
    const std::vector<float> droplet_before(mesh.vertices.begin() + 3 * std::ptrdiff_t(std::find(labels.begin(), labels.end(), 1) - labels.begin()),
                                            mesh.vertices.end());
    laplacian_smooth(mesh, weights, 25, 1.0, 2);
    const double shrunk = component_volumes(mesh, labels, count)[0];
    CHECK(shrunk < 0.97 * target[0]);
    restore_component_volumes(mesh, build_adjacency(mesh, 2), unsmoothed, weights, 0.5, 10, 2);
    const auto after = component_volumes(mesh, labels, count);
    CHECK(after[0] == Approx(target[0]).epsilon(1e-3));
    CHECK(after[1] == Approx(target[1]).epsilon(1e-9));
    const std::vector<float> droplet_after(mesh.vertices.begin() + std::ptrdiff_t(mesh.vertices.size() - droplet_before.size()), mesh.vertices.end());
    CHECK(droplet_after == droplet_before);
    CHECK(check_mesh(mesh).ok());
}

TEST_CASE("a component that smoothing collapses keeps its raw positions", "[volume]") {
    // An octahedron (a blob around one grid point): one uniform step moves every vertex to the centre.
    TriMesh mesh = make_octasphere(0, 0.01, {1, 2, 3});
    append(mesh, make_icosphere(3, 1.0));
    const UnsmoothedSurface unsmoothed = record_unsmoothed_surface(mesh, 1);
    const std::vector<float>& before = unsmoothed.positions;
    laplacian_smooth(mesh, {}, 25, 1.0, 1);
    REQUIRE_FALSE(check_mesh(mesh).ok());
    CHECK(revert_collapsed_components(mesh, unsmoothed, 1) == 1);
    CHECK(check_mesh(mesh).ok());
    for (std::size_t v = 0; v < 6; ++v)
        for (int k = 0; k < 3; ++k) CHECK(mesh.vertices[3 * v + k] == before[3 * v + k]);
}
