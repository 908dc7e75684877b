// Mesh cleanup (post/mesh_cleanup.h): merging the vertices that share a lattice point.
#include <catch2/catch.hpp>


#include "analysis/quality.h"
#include "base/errors.h"
#include "mesh/topology.h"
#include "mesh_builders.h"
#include "post/mesh_cleanup.h"

using namespace meniscus;
using namespace meniscus::test;

TEST_CASE("mesh cleanup merges vertices sharing a lattice point", "[cleanup]") {
    const double h = 0.07;  // the sampling box starts on a lattice point (-19 h), like marching cubes' grid
    TriMesh m = marching_tetrahedra(blob, {-1.33, -1.33, -1.33}, {1.33, 1.33, 1.33}, h);
    REQUIRE(check_mesh(m).ok());
    // An attribute equal to x: averaged like the positions, it must still equal x afterwards.
    Attribute x{"x", 1, {}};
    for (std::size_t v = 0; v < m.num_vertices(); ++v) x.values.push_back(m.vertices[3 * v]);
    m.attributes.push_back(x);
    const std::size_t vertices = m.num_vertices();
    const double volume = assess_quality(m).volume;
    TriMesh two = m;
    const std::size_t removed = mesh_cleanup(m, h, -1.0, 1);
    mesh_cleanup(two, h, -1.0, 2);
    CHECK(m.vertices == two.vertices);
    CHECK(m.triangles == two.triangles);
    CHECK(removed == vertices - m.num_vertices());
    CHECK(m.num_vertices() < vertices * 8 / 10);
    const MeshQuality q = assess_quality(m);
    INFO(q.check.summary());
    CHECK(q.check.ok());
    CHECK(q.check.unreferenced_vertices == 0);
    CHECK(q.volume == Approx(volume).epsilon(0.02));
    for (std::size_t v = 0; v < m.num_vertices(); ++v) CHECK(m.attributes[0].values[v] == Approx(m.vertices[3 * v]).margin(1e-5));

    // A snap distance keeps vertices far from lattice points out of it.
    TriMesh fresh = marching_tetrahedra(blob, {-1.33, -1.33, -1.33}, {1.33, 1.33, 1.33}, h);
    const std::size_t limited = mesh_cleanup(fresh, h, 0.2, 2);
    CHECK(limited > 0);
    CHECK(limited < removed);
    CHECK(check_mesh(fresh).ok());
}

TEST_CASE("mesh cleanup refuses a cube edge that is not positive", "[cleanup]") {
    TriMesh n = make_cube();
    CHECK_THROWS_AS(mesh_cleanup(n, 0.0, -1.0, 1), InputError);
}
