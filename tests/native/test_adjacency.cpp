// Mesh connectivity (mesh/adjacency.h): one-rings, triangle fans and edges, the same for any thread count.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cstdint>
#include <vector>

#include "mesh/adjacency.h"
#include "mesh_builders.h"

using namespace meniscus;
using namespace meniscus::test;

TEST_CASE("adjacency: one-rings, edges and their triangles", "[adjacency]") {
    const TriMesh m = make_icosphere(2);
    const MeshAdjacency adj = build_adjacency(m, 2);
    REQUIRE(adj.vertex_neighbours.rows() == m.num_vertices());
    std::size_t fives = 0;
    for (std::size_t v = 0; v < m.num_vertices(); ++v) {
        CHECK(adj.vertex_triangles.size(v) == adj.valence(v));  // closed manifold: as many triangles as neighbours
        fives += adj.valence(v) == 5 ? 1 : 0;
        for (int64_t k = adj.vertex_neighbours.begin(v) + 1; k < adj.vertex_neighbours.end(v); ++k)
            CHECK(adj.vertex_neighbours.items[k - 1] < adj.vertex_neighbours.items[k]);
    }
    CHECK(fives == 12);
    // Every undirected edge, seen once from its smaller vertex, has two triangles: 3F/2 edges on a closed mesh.
    std::size_t edges = 0;
    std::vector<EdgeIncidence> incidences;
    for (std::size_t v = 0; v < m.num_vertices(); ++v) {
        upper_edge_incidences(m, adj.vertex_triangles, static_cast<int32_t>(v), incidences);
        for_each_edge(incidences, [&](const EdgeIncidence* first, const EdgeIncidence* last) {
            ++edges;
            CHECK(first->other > static_cast<int32_t>(v));
            CHECK(last - first == 2);
            CHECK(first[0].direction == -first[1].direction);  // oriented: traversed once each way
        });
    }
    CHECK(edges == 3 * m.num_triangles() / 2);
    // Built the same way for any thread count.
    const MeshAdjacency one = build_adjacency(m, 1);
    CHECK(one.vertex_triangles.items == adj.vertex_triangles.items);
    CHECK(one.vertex_neighbours.items == adj.vertex_neighbours.items);
}

TEST_CASE("adjacency: one-rings of open meshes and degenerate triangles match a brute-force count", "[adjacency]") {
    // A closed mesh takes the direct path (as many neighbours as triangles); a hole, a fin sharing an edge with
    // two triangles (non-manifold) and a triangle with a repeated index take the general one.
    TriMesh closed = make_icosphere(2);
    TriMesh open = closed;
    open.triangles.resize(open.triangles.size() - 3 * 5);  // five triangles gone: a hole
    TriMesh odd = closed;
    add_vertex(odd, {0.0, 0.0, 3.0});
    const std::vector<int32_t> first(odd.triangles.begin(), odd.triangles.begin() + 6);
    add_triangle(odd, first[0], first[1], static_cast<int32_t>(odd.num_vertices() - 1));  // a fin on the first edge
    add_triangle(odd, first[3], first[3], first[4]);                                      // a repeated index
    for (const TriMesh* m : {&closed, &open, &odd}) {
        const MeshAdjacency adj = build_adjacency(*m, 2);
        std::vector<std::vector<int32_t>> expected(m->num_vertices());
        for (std::size_t t = 0; t < m->num_triangles(); ++t)
            for (int a = 0; a < 3; ++a)
                for (int b = 0; b < 3; ++b) {
                    const int32_t u = m->triangles[3 * t + a], w = m->triangles[3 * t + b];
                    if (u != w) expected[u].push_back(w);
                }
        for (std::size_t v = 0; v < m->num_vertices(); ++v) {
            std::sort(expected[v].begin(), expected[v].end());
            expected[v].erase(std::unique(expected[v].begin(), expected[v].end()), expected[v].end());
            const std::vector<int32_t> row(adj.vertex_neighbours.row(v), adj.vertex_neighbours.row(v) + adj.valence(v));
            CHECK(row == expected[v]);
        }
    }
}
