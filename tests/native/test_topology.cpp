// The consistency check (mesh/topology.h): closed, manifold, oriented, and every way a mesh can fail it.
#include <catch2/catch.hpp>

#include <cmath>
#include <string>

#include "base/errors.h"
#include "mesh/topology.h"
#include "mesh_builders.h"

using namespace meniscus;
using namespace meniscus::test;

TEST_CASE("check_mesh accepts closed oriented manifolds", "[topology]") {
    for (const TriMesh& m : {make_icosphere(2), make_cube(), make_torus(2.0, 0.5, 24, 12), make_octasphere(1)}) {
        const MeshCheck c = check_mesh(m);
        CHECK(c.ok());
        CHECK(c.unreferenced_vertices == 0);
        CHECK(c.summary() == "closed, manifold, oriented");
    }
}

TEST_CASE("check_mesh finds a hole", "[topology]") {
    TriMesh m = make_icosphere(1);
    m.triangles.resize(m.triangles.size() - 3);
    const MeshCheck c = check_mesh(m);
    CHECK(c.boundary_edges == 3);
    CHECK_FALSE(c.closed());
    CHECK(c.manifold());
    CHECK(c.oriented());
    CHECK_FALSE(c.ok());
    CHECK(c.summary().find("3 boundary edges") != std::string::npos);
}

TEST_CASE("check_mesh finds a flipped triangle", "[topology]") {
    TriMesh m = make_icosphere(1);
    std::swap(m.triangles[4], m.triangles[5]);
    const MeshCheck c = check_mesh(m);
    CHECK(c.inconsistent_edges == 3);
    CHECK(c.closed());
    CHECK_FALSE(c.oriented());
    CHECK_FALSE(c.ok());
}

TEST_CASE("check_mesh finds a non-manifold edge", "[topology]") {
    TriMesh m = make_icosphere(1);
    // A fin on edge (t0, t1) of the first triangle: that edge now has three triangles.
    const int32_t a = m.triangles[0], b = m.triangles[1];
    const int32_t tip = add_vertex(m, {0.0, 0.0, 3.0});
    add_triangle(m, a, b, tip);
    const MeshCheck c = check_mesh(m);
    CHECK(c.non_manifold_edges == 1);
    CHECK(c.boundary_edges == 2);
    CHECK_FALSE(c.manifold());
}

TEST_CASE("check_mesh finds a bow-tie vertex", "[topology]") {
    // Two cubes touching at one corner: every edge has two triangles, but the shared vertex has two fans.
    TriMesh m = make_cube();
    TriMesh other = make_cube();
    for (float& x : other.vertices) x += 1.0f;  // corner 0 of `other` sits on corner 7 of m
    append(m, other);
    for (int32_t& i : m.triangles)
        if (i == 8) i = 7;
    const MeshCheck c = check_mesh(m);
    CHECK(c.non_manifold_vertices == 1);
    CHECK(c.non_manifold_edges == 0);
    CHECK(c.boundary_edges == 0);
    CHECK(c.unreferenced_vertices == 1);  // the merged-away corner
    CHECK_FALSE(c.manifold());
}

TEST_CASE("check_mesh finds degenerate triangles, non-finite and unreferenced vertices", "[topology]") {
    TriMesh m = make_icosphere(1);
    add_vertex(m, {5, 5, 5});                 // unreferenced
    m.vertices[0] = std::nanf("");            // non-finite
    add_triangle(m, 1, 1, 2);                 // repeated index
    const int32_t p = add_vertex(m, {0, 0, 0}), q = add_vertex(m, {1, 0, 0}), r = add_vertex(m, {2, 0, 0});
    add_triangle(m, p, q, r);                 // collinear: zero area
    const MeshCheck c = check_mesh(m);
    CHECK(c.degenerate_triangles == 2);
    CHECK(c.non_finite_vertices == 1);
    CHECK(c.unreferenced_vertices == 1);
    CHECK_FALSE(c.ok());
}

TEST_CASE("check_mesh refuses out-of-range indices", "[topology]") {
    TriMesh m = make_cube();
    m.triangles[5] = 42;
    CHECK_THROWS_AS(check_mesh(m), InputError);
}
