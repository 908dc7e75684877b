// Barnacle decimation (post/decimation.h, Sec. 3.3) on planted configurations, irregular and broken meshes and
// real marching-cubes output.
#include <catch2/catch.hpp>

#include <cstdint>
#include <vector>

#include "analysis/quality.h"
#include "base/errors.h"
#include "mesh/adjacency.h"
#include "mesh/topology.h"
#include "mesh_builders.h"
#include "post/decimation.h"
#include "post/normals.h"
#include "surface/reconstruction.h"

using namespace meniscus;
using namespace meniscus::test;

TEST_CASE("planted barnacles are detected", "[decimation]") {
    std::size_t singles = 0, doubles = 0;
    const TriMesh m = barnacle_sphere(singles, doubles);
    REQUIRE(singles == 6);
    REQUIRE(doubles >= 4);
    CHECK(check_mesh(m).ok());
    CHECK(faces_outward(m));
    CHECK(count_single_vertex_configurations(m) == singles);
    CHECK(count_double_vertex_configurations(m) == doubles);
    CHECK(count_single_vertex_configurations(make_icosphere(3)) == 0);
    CHECK(count_double_vertex_configurations(make_icosphere(3)) == 0);
}

TEST_CASE("decimation removes all barnacles and keeps the mesh valid", "[decimation]") {
    std::size_t singles = 0, doubles = 0;
    TriMesh m = barnacle_sphere(singles, doubles);
    add_index_attribute(m);
    compute_area_weighted_normals(m, 1);
    const TriMesh original = m;
    const std::size_t removed = decimate_barnacles(m, 2);
    CHECK(removed == singles + doubles);
    CHECK(count_single_vertex_configurations(m) == 0);
    CHECK(count_double_vertex_configurations(m) == 0);
    const MeshCheck c = check_mesh(m);
    INFO(c.summary());
    CHECK(c.ok());
    CHECK(c.unreferenced_vertices == 0);
    CHECK(faces_outward(m));
    // Each single removes its 4 ring vertices, each double its 6.
    CHECK(m.num_vertices() == original.num_vertices() - 4 * singles - 6 * doubles);
    CHECK(m.num_triangles() == original.num_triangles() - 8 * singles - 12 * doubles);
    // Survivors keep their own position, normal and attributes.
    REQUIRE(m.attributes.size() == 1);
    REQUIRE(m.attributes[0].values.size() == m.num_vertices());
    REQUIRE(m.normals.size() == m.vertices.size());
    for (std::size_t v = 0; v < m.num_vertices(); ++v) {
        const int64_t o = static_cast<int64_t>(m.attributes[0].values[v]);
        for (int k = 0; k < 3; ++k) {
            CHECK(m.vertices[3 * v + k] == original.vertices[3 * o + k]);
            CHECK(m.normals[3 * v + k] == original.normals[3 * o + k]);
        }
    }
}

TEST_CASE("decimation is independent of the thread count", "[decimation]") {
    std::size_t singles = 0, doubles = 0;
    TriMesh a = barnacle_sphere(singles, doubles);
    TriMesh b = a;
    decimate_barnacles(a, 1);
    decimate_barnacles(b, 2);
    CHECK(a.vertices == b.vertices);
    CHECK(a.triangles == b.triangles);
}

TEST_CASE("decimation handles neighbouring barnacles", "[decimation]") {
    // All six single configurations of a coarse octasphere touch each other's two-rings.
    TriMesh m = make_octasphere(1);
    for (int32_t v = 0; v < 6; ++v) insert_single_configuration(m, v);
    REQUIRE(check_mesh(m).ok());
    REQUIRE(count_single_vertex_configurations(m) > 0);
    decimate_barnacles(m, 2);
    CHECK(check_mesh(m).ok());
    CHECK(count_single_vertex_configurations(m) == 0);
    CHECK(count_double_vertex_configurations(m) == 0);
}

TEST_CASE("decimation of a marching-tetrahedra mesh keeps it valid", "[decimation]") {
    TriMesh m = marching_tetrahedra(blob, {-1.33, -1.33, -1.33}, {1.33, 1.33, 1.33}, 0.07);
    REQUIRE(check_mesh(m).ok());
    const std::size_t before = count_single_vertex_configurations(m) + count_double_vertex_configurations(m);
    const double volume = assess_quality(m).volume;
    TriMesh again = m;
    decimate_barnacles(m, 2);
    decimate_barnacles(again, 1);
    CHECK(m.triangles == again.triangles);
    const MeshQuality q = assess_quality(m);
    INFO(q.check.summary());
    CHECK(q.check.ok());
    CHECK(q.single_vertex_configurations + q.double_vertex_configurations <= before);
    CHECK(q.volume == Approx(volume).epsilon(0.01));
}

TEST_CASE("decimation does not crash on broken input", "[decimation]") {
    std::size_t singles = 0, doubles = 0;
    TriMesh m = barnacle_sphere(singles, doubles);
    // Open it (a hole), add a fin (non-manifold edge) and a repeated-index triangle.
    m.triangles.erase(m.triangles.begin(), m.triangles.begin() + 3);
    const int32_t tip = add_vertex(m, {0, 0, 5});
    add_triangle(m, m.triangles[0], m.triangles[1], tip);
    add_triangle(m, 3, 3, 4);
    const MeshCheck before = check_mesh(m);
    decimate_barnacles(m, 2);
    const MeshCheck after = check_mesh(m);
    CHECK(after.boundary_edges <= before.boundary_edges);
    CHECK(after.non_manifold_edges <= before.non_manifold_edges);
    CHECK(after.inconsistent_edges == 0);
}

TEST_CASE("decimation hands over the adjacency of the mesh it leaves", "[decimation]") {
    auto same = [](const CsrList& a, const CsrList& b) { return a.offsets == b.offsets && a.items == b.items; };
    std::size_t singles = 0, doubles = 0;
    TriMesh changed = barnacle_sphere(singles, doubles);
    MeshAdjacency handed;
    REQUIRE(decimate_barnacles(changed, 2, &handed) > 0);
    const MeshAdjacency rebuilt = build_adjacency(changed, 1);
    REQUIRE(handed.vertex_triangles.rows() == changed.num_vertices());
    CHECK(same(handed.vertex_triangles, rebuilt.vertex_triangles));
    CHECK(same(handed.vertex_neighbours, rebuilt.vertex_neighbours));

    // Neighbouring configurations are deferred to later passes, whose adjacency is patched rather than rebuilt.
    TriMesh crowded = make_octasphere(1);
    for (int32_t v = 0; v < 6; ++v) insert_single_configuration(crowded, v);
    decimate_barnacles(crowded, 2, &handed);
    const MeshAdjacency crowded_rebuilt = build_adjacency(crowded, 1);
    REQUIRE(handed.vertex_triangles.rows() == crowded.num_vertices());
    CHECK(same(handed.vertex_triangles, crowded_rebuilt.vertex_triangles));
    CHECK(same(handed.vertex_neighbours, crowded_rebuilt.vertex_neighbours));

    TriMesh unchanged = make_icosphere(3);  // nothing to decimate: the detection pass's adjacency is handed over
    REQUIRE(decimate_barnacles(unchanged, 2, &handed) == 0);
    const MeshAdjacency built = build_adjacency(unchanged, 1);
    CHECK(same(handed.vertex_triangles, built.vertex_triangles));
    CHECK(same(handed.vertex_neighbours, built.vertex_neighbours));
}

TEST_CASE("decimation refuses out-of-range indices", "[decimation]") {
    TriMesh m = make_cube();
    m.triangles[5] = 42;
    CHECK_THROWS_AS(decimate_barnacles(m, 1), InputError);
}

TEST_CASE("decimation of real marching-cubes meshes hands over the adjacency a rebuild gives", "[decimation][reconstruction]") {
    // Droplets (single particles and pairs) at c = 1.0: their blobs carry several barnacles each, close together,
    // so later decimation passes run on patched adjacencies.
    // Large enough for several blocks of rows in the parallel dropping of removed vertices' rows; at several thread
    // counts, each the same mesh.
    const std::vector<float> positions = droplet_particles(11, 30);
    const TriMesh reconstructed =
        reconstruct_surface(PositionsView(positions.data(), positions.size() / 3), reconstruction_params(0.025, 1.0), {}).mesh;
    REQUIRE(reconstructed.num_vertices() > 3 * 16384);
    TriMesh first;
    for (int threads : {2, 3, 7}) {
        INFO(threads << " threads");
        TriMesh mesh = reconstructed;
        MeshAdjacency handed;
        REQUIRE(decimate_barnacles(mesh, threads, &handed) > 5);
        const MeshAdjacency rebuilt = build_adjacency(mesh, 1);
        REQUIRE(handed.vertex_triangles.rows() == mesh.num_vertices());
        CHECK(handed.vertex_triangles.offsets == rebuilt.vertex_triangles.offsets);
        CHECK(handed.vertex_triangles.items == rebuilt.vertex_triangles.items);
        CHECK(handed.vertex_neighbours.offsets == rebuilt.vertex_neighbours.offsets);
        CHECK(handed.vertex_neighbours.items == rebuilt.vertex_neighbours.items);
        CHECK(count_single_vertex_configurations(mesh) == 0);
        CHECK(count_double_vertex_configurations(mesh) == 0);
        CHECK(check_mesh(mesh).ok());
        if (first.triangles.empty()) first = mesh;
        CHECK(mesh.triangles == first.triangles);
        CHECK(mesh.vertices == first.vertices);
    }
}
