// The parallel building blocks and the default pipeline give the same bits at every thread count, and the parallel
// versions of once-serial steps give what the serial ones gave (base/compaction.h, base/concurrent_disjoint_sets.h,
// the vertex -> triangle lists, component labels, surface aggregates, the greedy selection of disjoint sets, the
// particle grid).
#include <catch2/catch.hpp>

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <vector>

#include "base/compaction.h"
#include "base/concurrent_disjoint_sets.h"
#include "base/greedy_selection.h"
#include "base/parallel_move.h"
#include "base/uninitialized_vector.h"
#include "io/io.h"
#include "mesh/adjacency.h"
#include "mesh/components.h"
#include "mesh_builders.h"
#include "test_files.h"
#include "pipeline.h"
#include "post/surface_aggregates.h"
#include "sph/neighborhood.h"
#include "surface/reconstruction.h"

using namespace meniscus;
using namespace meniscus::test;

namespace {

const int kThreadCounts[] = {1, 2, 3, 4, 7};

TriMesh droplet_mesh() {
    const std::vector<float> positions = droplet_particles(11, 12);
    return reconstruct_surface(PositionsView(positions.data(), positions.size() / 3), reconstruction_params(0.025, 1.0), {}).mesh;
}

}  // namespace

TEST_CASE("order-keeping compaction numbers the kept items as a serial loop does", "[threads]") {
    const int64_t n = 3 * kCompactionBlock + 17;  // several blocks and a partial one
    auto keep = [](int64_t i) { return (i * 2654435761u) % 7 < 3; };
    std::vector<int32_t> serial_index(static_cast<std::size_t>(n), -1), serial_kept;
    for (int64_t i = 0; i < n; ++i)
        if (keep(i)) serial_index[i] = static_cast<int32_t>(serial_kept.size()), serial_kept.push_back(static_cast<int32_t>(i));
    REQUIRE(serial_kept.size() > static_cast<std::size_t>(kCompactionBlock));
    for (int threads : kThreadCounts) {
        std::vector<int32_t> index(static_cast<std::size_t>(n), 99);
        CHECK(number_kept(n, threads, keep, index.data()) == static_cast<int64_t>(serial_kept.size()));
        CHECK(index == serial_index);
        CHECK(kept_indices(n, threads, keep) == serial_kept);
    }
    CHECK(kept_indices(0, 2, keep).empty());
}

TEST_CASE("concurrent disjoint sets end with the smallest element as every set's root", "[threads]") {
    // Chains 0-3-6-..., 1-4-7-..., 2-5-8-... united from the far end, in parallel.
    const int32_t n = 30000;
    ConcurrentDisjointSets sets(n, 4);
    parallel_for(n - 3, 4, [&](int64_t i) { sets.unite(static_cast<int32_t>(n - 1 - i), static_cast<int32_t>(n - 4 - i)); });
    for (int32_t v = 0; v < n; ++v) REQUIRE(sets.find(v) == v % 3);
}

TEST_CASE("items grouped by key: ascending rows, the same at every thread count", "[threads][adjacency]") {
    // Keys of a skewed spread (many small groups, a few large ones, some empty) over several blocks.
    const int64_t n = 50000;
    const int32_t groups = 3001;
    std::vector<int32_t> keys(static_cast<std::size_t>(n));
    for (int64_t i = 0; i < n; ++i) keys[i] = static_cast<int32_t>((i * 7919 + (i % 13) * (i % 13) * 31) % (groups - 1));
    std::vector<std::vector<int32_t>> expected(static_cast<std::size_t>(groups));
    for (int64_t i = 0; i < n; ++i) expected[keys[i]].push_back(static_cast<int32_t>(i));
    for (int threads : kThreadCounts) {
        INFO(threads << " threads");
        const CsrList list = group_by_key(keys.data(), n, groups, threads);
        REQUIRE(list.rows() == static_cast<std::size_t>(groups));
        for (int32_t g = 0; g < groups; ++g) REQUIRE(std::vector<int32_t>(list.row(g), list.row(g) + list.size(g)) == expected[g]);
    }
}

TEST_CASE("vertex -> triangle lists are the serial counting sort's at every thread count", "[threads][adjacency]") {
    TriMesh mesh = droplet_mesh();
    REQUIRE(mesh.num_triangles() > 10000);
    // A repeated index is listed once per distinct vertex.
    mesh.triangles.insert(mesh.triangles.end(), {5, 5, 9, 7, 8, 7, 3, 3, 3});
    const CsrList serial = build_vertex_triangles(mesh, 1);
    for (int64_t v = 0; v < static_cast<int64_t>(serial.rows()); ++v)
        REQUIRE(std::is_sorted(serial.items.begin() + serial.offsets[v], serial.items.begin() + serial.offsets[v + 1]));
    for (int threads : kThreadCounts) {
        const CsrList parallel = build_vertex_triangles(mesh, threads);
        CHECK(parallel.offsets == serial.offsets);
        CHECK(parallel.items == serial.items);
    }
    // Triangles in no particular order: every block of them spans every thread's vertices, so from 3 threads on the
    // lists come from the atomic counting instead of the owned ranges. The same lists either way.
    TriMesh shuffled = mesh;
    const int64_t nt = static_cast<int64_t>(shuffled.num_triangles());
    for (int64_t t = nt - 1; t > 0; --t) {  // a fixed permutation (no random generator: the same on every platform)
        const int64_t other = (t * 7919 + 13) % (t + 1);
        for (int k = 0; k < 3; ++k) std::swap(shuffled.triangles[3 * t + k], shuffled.triangles[3 * other + k]);
    }
    const CsrList shuffled_serial = build_vertex_triangles(shuffled, 1);
    for (int threads : kThreadCounts) {
        INFO("shuffled, " << threads << " threads");
        const CsrList parallel = build_vertex_triangles(shuffled, threads);
        CHECK(parallel.offsets == shuffled_serial.offsets);
        CHECK(parallel.items == shuffled_serial.items);
    }
}

TEST_CASE("adjacency rows over several scan blocks hold each vertex's own triangles and neighbours", "[threads][adjacency]") {
    // An icosphere of 163 842 vertices (several blocks of the row-start scan) with every seventh triangle taken out,
    // so the neighbour lists take the general path (open fans) and its scan too; rows checked against direct counts.
    TriMesh mesh = make_icosphere(7);
    REQUIRE(mesh.num_vertices() > 2 * 65536);
    std::vector<int32_t> kept;
    for (std::size_t t = 0; t < mesh.num_triangles(); ++t)
        if (t % 7 != 3) kept.insert(kept.end(), mesh.triangles.begin() + 3 * t, mesh.triangles.begin() + 3 * t + 3);
    mesh.triangles = kept;
    std::vector<int64_t> triangles_of(mesh.num_vertices(), 0);
    for (int32_t v : mesh.triangles) ++triangles_of[v];
    std::vector<std::pair<int32_t, int32_t>> edges;  // (vertex, neighbour), both directions
    for (std::size_t t = 0; t < mesh.num_triangles(); ++t)
        for (int k = 0; k < 3; ++k) {
            const int32_t a = mesh.triangles[3 * t + k], b = mesh.triangles[3 * t + (k + 1) % 3];
            edges.push_back({a, b}), edges.push_back({b, a});
        }
    std::sort(edges.begin(), edges.end());
    edges.erase(std::unique(edges.begin(), edges.end()), edges.end());
    UninitializedVector<int32_t> expected_neighbours;
    std::vector<int64_t> neighbours_of(mesh.num_vertices(), 0);
    for (const auto& e : edges) expected_neighbours.push_back(e.second), ++neighbours_of[e.first];
    for (int threads : kThreadCounts) {
        INFO(threads << " threads");
        const MeshAdjacency adjacency = build_adjacency(mesh, threads);
        bool rows_match = true;
        for (std::size_t v = 0; v < mesh.num_vertices(); ++v)
            rows_match = rows_match && adjacency.vertex_triangles.size(v) == triangles_of[v] && adjacency.vertex_neighbours.size(v) == neighbours_of[v];
        CHECK(rows_match);
        CHECK(adjacency.vertex_neighbours.items == expected_neighbours);
        CHECK(adjacency.vertex_neighbours.offsets.back() > adjacency.vertex_triangles.offsets.back());  // the general path ran
    }
}

TEST_CASE("component labels are numbered by smallest vertex at every thread count", "[threads][components]") {
    const TriMesh mesh = droplet_mesh();
    // The reference: a breadth-first search from each vertex not yet labelled, in vertex order.
    const MeshAdjacency adjacency = build_adjacency(mesh, 1);
    std::vector<int32_t> expected(mesh.num_vertices(), -1);
    int32_t expected_count = 0;
    for (std::size_t start = 0; start < expected.size(); ++start) {
        if (expected[start] >= 0) continue;
        std::vector<int32_t> queue{static_cast<int32_t>(start)};
        expected[start] = expected_count;
        for (std::size_t q = 0; q < queue.size(); ++q)
            for (int64_t k = adjacency.vertex_neighbours.begin(queue[q]); k < adjacency.vertex_neighbours.end(queue[q]); ++k) {
                const int32_t u = adjacency.vertex_neighbours.items[k];
                if (expected[u] < 0) expected[u] = expected_count, queue.push_back(u);
            }
        ++expected_count;
    }
    REQUIRE(expected_count > 100);
    for (int threads : kThreadCounts) {
        int32_t count = 0;
        CHECK(component_labels(mesh, &count, threads) == expected);
        CHECK(count == expected_count);
    }
}

TEST_CASE("surface aggregates are the same at every thread count", "[threads][aggregates]") {
    const TriMesh mesh = droplet_mesh();
    const MeshAdjacency adjacency = build_adjacency(mesh, 1);
    const SurfaceAggregates one = aggregate_surface(mesh, adjacency, 0.05, 1);
    REQUIRE(one.size() > 100);
    for (int threads : kThreadCounts) {
        const SurfaceAggregates g = aggregate_surface(mesh, adjacency, 0.05, threads);
        CHECK(g.of_vertex == one.of_vertex);
        CHECK(g.members.items == one.members.items);
        CHECK(g.neighbours.items == one.neighbours.items);
        CHECK(g.coupling == one.coupling);
    }
}

TEST_CASE("the default pipeline gives the same bits at 1, 2, 3, 4 and 7 threads", "[threads][determinism]") {
    const ParticleData particles = read_particles(shared_frame("splashsurf/hilbert2_7954_particles.vtk"));
    for (double cube : {0.5, 1.0}) {
        PipelineOptions options;  // the defaults: decimation, weights, the reach's heat flow, normals
        options.reconstruction = reconstruction_params(0.025, cube);
        options.execution.threads = 1;
        const PipelineResult one = run_pipeline(PositionsView(particles.positions.data(), particles.size()), {}, options);
        REQUIRE(one.mesh.num_triangles() > 0);
        for (int threads : kThreadCounts) {
            options.execution.threads = threads;
            const PipelineResult other = run_pipeline(PositionsView(particles.positions.data(), particles.size()), {}, options);
            INFO("c = " << cube << ", " << threads << " threads");
            CHECK(other.mesh.vertices == one.mesh.vertices);
            CHECK(other.mesh.triangles == one.mesh.triangles);
            CHECK(other.mesh.normals == one.mesh.normals);
        }
    }
}

TEST_CASE("mesh files have the same bytes whatever the number of encoding threads", "[threads][io]") {
    TriMesh mesh = make_icosphere(7);
    REQUIRE(mesh.num_vertices() > 3 * 16384);  // several blocks of records
    mesh.normals.assign(mesh.vertices.size(), 0.5f);
    mesh.attributes.push_back({"id", 1, std::vector<float>(mesh.num_vertices(), 7.0f), true});
    const TempDir dir("threads");
    for (const std::string extension : {".ply", ".obj", ".vtk"}) {
        write_mesh(mesh, dir.file("one" + extension), 1);
        const Bytes one = read_bytes(dir.file("one" + extension));
        REQUIRE(one.size() > 100000);
        for (int threads : {2, 3, 7}) {
            write_mesh(mesh, dir.file("many" + extension), threads);
            CHECK(read_bytes(dir.file("many" + extension)) == one);
        }
        const TriMesh back = read_mesh(dir.file("one" + extension));
        CHECK(back.triangles == mesh.triangles);
        CHECK(back.vertices == mesh.vertices);
    }
}

TEST_CASE("volumes of very many components are summed in parallel with the same bits at every thread count", "[threads][components]") {
    // 300 000 separate tetrahedra: more components x blocks than one row per block of triangles allows, so the sums
    // run over fewer, longer blocks (mesh/components.h) instead of one serial pass.
    TriMesh mesh;
    const int tetrahedra = 300000;
    for (int i = 0; i < tetrahedra; ++i) {
        const float x = static_cast<float>(i % 1000) * 2.0f, y = static_cast<float>(i / 1000) * 2.0f;
        const int32_t a = add_vertex(mesh, {x, y, 0}), b = add_vertex(mesh, {x + 1, y, 0}), c = add_vertex(mesh, {x, y + 1, 0}),
                      d = add_vertex(mesh, {x, y, 1});
        add_triangle(mesh, a, c, b), add_triangle(mesh, a, b, d), add_triangle(mesh, a, d, c), add_triangle(mesh, b, c, d);
    }
    int32_t count = 0;
    const std::vector<int32_t> labels = component_labels(mesh, &count, 4);
    REQUIRE(count == tetrahedra);
    const std::vector<double> one = component_volumes(mesh, labels, count, 1);
    for (double volume : one) REQUIRE(volume == Approx(1.0 / 6.0));
    for (int threads : {2, 3, 7}) CHECK(component_volumes(mesh, labels, count, threads) == one);
}

TEST_CASE("the parallel greedy selection takes the sets a serial greedy pass takes, at every thread count", "[threads][decimation]") {
    // 6 000 sets of 12 vertices from a sliding window over 20 000 vertices: long chains of conflicts.
    const int32_t vertex_count = 20000;
    std::vector<std::vector<int32_t>> regions(6000);
    uint32_t state = 12345;
    auto next = [&] { return state = state * 1664525u + 1013904223u, state >> 8; };
    for (std::size_t i = 0; i < regions.size(); ++i) {
        const int32_t window = static_cast<int32_t>(next() % (vertex_count - 60));
        for (int k = 0; k < 12; ++k) regions[i].push_back(window + static_cast<int32_t>(next() % 60));
    }
    std::vector<int32_t> before(vertex_count, -1);
    before[100] = 2;  // a mark of an earlier pass does not count
    std::vector<int32_t> serial_claim = before;
    std::vector<uint8_t> serial_taken(regions.size(), 0);
    for (std::size_t i = 0; i < regions.size(); ++i) {
        bool free = true;
        for (int32_t v : regions[i]) free = free && serial_claim[v] != 3;
        if (!free) continue;
        serial_taken[i] = 1;
        for (int32_t v : regions[i]) serial_claim[v] = 3;
    }
    const std::size_t taken_count = static_cast<std::size_t>(std::count(serial_taken.begin(), serial_taken.end(), 1));
    REQUIRE(taken_count > 50);
    REQUIRE(taken_count < regions.size() / 2);
    for (int threads : kThreadCounts) {
        std::vector<int32_t> claim = before;
        std::vector<std::atomic<int32_t>> lowest(vertex_count);
        INFO(threads << " threads");
        CHECK(select_greedy_disjoint(regions, claim, 3, lowest, threads) == serial_taken);
        CHECK(claim == serial_claim);
    }
}

TEST_CASE("the particle grid is the same at every thread count, sorted by cell and then input order", "[threads][sph]") {
    // 300 000 particles (several blocks of the parallel radix sort) in a box of 40^3 cells, every fifth left out.
    const std::size_t n = 300000;
    const double cell = 0.1;
    std::vector<float> positions(3 * n);
    uint32_t state = 777;
    for (float& x : positions) state = state * 1664525u + 1013904223u, x = static_cast<float>((state >> 8) % 4000000) * 1.0e-6f - 1.7f;
    std::vector<uint8_t> keep(n);
    for (std::size_t i = 0; i < n; ++i) keep[i] = i % 5 != 2;
    auto cell_of = [&](uint32_t i) {
        std::array<int64_t, 3> c;
        for (int k = 0; k < 3; ++k) c[k] = static_cast<int64_t>(std::floor(double(positions[3 * i + k]) / cell));
        return std::array<int64_t, 3>{c[2], c[1], c[0]};
    };
    UninitializedVector<uint32_t> expected;
    for (uint32_t i = 0; i < n; ++i)
        if (keep[i]) expected.push_back(i);
    std::stable_sort(expected.begin(), expected.end(), [&](uint32_t a, uint32_t b) { return cell_of(a) < cell_of(b); });
    const PositionsView view(positions.data(), n);
    const ParticleGrid one(view, cell, 1, &keep);
    REQUIRE(one.original_indices() == expected);
    REQUIRE(one.num_cells() > 50000);
    for (std::size_t c = 0; c < one.num_cells(); ++c) {
        const auto coords = one.cell_coords(c);
        REQUIRE(one.cell_begin(c) < one.cell_end(c));
        for (std::size_t j = one.cell_begin(c); j < one.cell_end(c); ++j) {
            const auto zyx = cell_of(one.original_index(j));
            REQUIRE(coords == std::array<int64_t, 3>{zyx[2], zyx[1], zyx[0]});
        }
    }
    for (int threads : kThreadCounts) {
        const ParticleGrid grid(view, cell, threads, &keep);
        INFO(threads << " threads");
        CHECK(grid.original_indices() == one.original_indices());
        CHECK(grid.positions() == one.positions());
        REQUIRE(grid.num_cells() == one.num_cells());
        bool same_cells = true;
        for (std::size_t c = 0; c < one.num_cells(); ++c)
            same_cells = same_cells && grid.cell_coords(c) == one.cell_coords(c) && grid.cell_begin(c) == one.cell_begin(c) &&
                         grid.cell_end(c) == one.cell_end(c);
        CHECK(same_cells);
    }
    // Coordinates too large for the grid: the first such particle is named, whichever thread meets it.
    positions[3 * 250001 + 1] = 1.0e30f;
    positions[3 * 70001] = -1.0e30f;
    for (int threads : {1, 4})
        CHECK_THROWS_WITH(ParticleGrid(view, cell, threads, &keep), Catch::Contains("particle 70001 has a coordinate too large"));
}

TEST_CASE("overlapping moves in parallel chunks equal memmove, up and down, at any distance", "[threads][move]") {
    const int64_t chunk = kMoveChunk;
    for (int64_t count : {int64_t{100}, 3 * chunk + 17, 9 * chunk}) {
        for (int64_t distance : {int64_t{1}, int64_t{3}, int64_t{299}, int64_t{5000}, chunk - 1, chunk, chunk + 5, 2 * chunk + 1, count + 3}) {
            for (bool down : {true, false}) {
                // Room for the move either way; values distinct, so a misplaced element shows.
                std::vector<int32_t> original(static_cast<std::size_t>(count + distance + 10));
                for (std::size_t i = 0; i < original.size(); ++i) original[i] = static_cast<int32_t>(i * 7 + 1);
                const int64_t from = down ? distance + 4 : 4, to = down ? 4 : distance + 4;
                std::vector<int32_t> expected = original;
                std::memmove(expected.data() + to, expected.data() + from, static_cast<std::size_t>(count) * sizeof(int32_t));
                for (int threads : {1, 2, 3, 7}) {
                    INFO("count " << count << ", distance " << distance << (down ? " down, " : " up, ") << threads << " threads");
                    std::vector<int32_t> moved = original;
                    move_in_parallel(moved.data(), from, to, count, threads);
                    CHECK(moved == expected);
                }
            }
        }
    }
}

TEST_CASE("parallel fills and copies write every element", "[threads][move]") {
    for (int threads : {1, 3}) {
        UninitializedVector<int64_t> filled;
        fill_in_parallel(filled, 200003, int64_t{-5}, threads);
        CHECK(filled.size() == 200003);
        CHECK(std::all_of(filled.begin(), filled.end(), [](int64_t v) { return v == -5; }));
        std::vector<int32_t> source(150001);
        for (std::size_t i = 0; i < source.size(); ++i) source[i] = static_cast<int32_t>(i ^ 0x5a5a);
        UninitializedVector<int32_t> copied;
        copy_in_parallel(source.data(), source.size(), copied, threads);
        CHECK(std::equal(copied.begin(), copied.end(), source.begin(), source.end()));
    }
}

TEST_CASE("mesh checks name the first index out of range at any thread count", "[threads][validation]") {
    TriMesh mesh = make_icosphere(5);
    const std::size_t nv = mesh.num_vertices();
    REQUIRE(mesh.triangles.size() > 60000);
    for (int threads : kThreadCounts) CHECK(first_index_out_of_range(mesh.triangles, nv, threads) == mesh.triangles.size());
    // Two bad indices far apart: the first one is named, whichever thread counts it.
    mesh.triangles[3 * 9000 + 2] = static_cast<int32_t>(nv);
    mesh.triangles[3 * 15000] = -4;
    for (int threads : kThreadCounts) {
        INFO(threads << " threads");
        CHECK(first_index_out_of_range(mesh.triangles, nv, threads) == 3 * 9000 + 2);
        CHECK_THROWS_WITH(validate_mesh_arrays(mesh, "check", threads),
                          Catch::Contains("triangle 9000 uses vertex index " + std::to_string(nv)));
    }
}
