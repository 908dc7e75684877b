// Tests of the post-processing stages (paper Sec. 3.3-3.4): topology check, quality report, smoothing, normals,
// barnacle decimation and mesh cleanup, on meshes built in code (mesh_builders.h).
#include <catch2/catch.hpp>

#include <cmath>
#include <vector>

#include "base/errors.h"
#include "mesh/adjacency.h"
#include "mesh_builders.h"
#include "post/postprocess.h"

using namespace meniscus;
using namespace meniscus::test;

namespace {

const double kPi = std::acos(-1.0);

bool all_finite(const std::vector<float>& values) {
    for (float x : values)
        if (!std::isfinite(x)) return false;
    return true;
}

// Every triangle of a sphere-like mesh centred at c faces away from c.
bool faces_outward(const TriMesh& m, V3 c = {0, 0, 0}) {
    for (std::size_t t = 0; t < m.num_triangles(); ++t) {
        const V3 a = vertex_of(m, m.triangles[3 * t]), b = vertex_of(m, m.triangles[3 * t + 1]), d = vertex_of(m, m.triangles[3 * t + 2]);
        const V3 e1{b[0] - a[0], b[1] - a[1], b[2] - a[2]}, e2{d[0] - a[0], d[1] - a[1], d[2] - a[2]};
        const V3 n{e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2], e1[0] * e2[1] - e1[1] * e2[0]};
        if (n[0] * (a[0] - c[0]) + n[1] * (a[1] - c[1]) + n[2] * (a[2] - c[2]) <= 0) return false;
    }
    return true;
}

// A bumpy blob: sphere of radius 1 with a few low-frequency waves, so marching cubes/tetrahedra of it produce
// every kind of sliver near lattice points.
double blob(double x, double y, double z) {
    const double r = std::sqrt(x * x + y * y + z * z);
    return 1.0 - r + 0.08 * std::sin(5.1 * x + 0.3) * std::sin(4.3 * y + 1.1) * std::sin(3.7 * z + 0.7);
}

// Test mesh with planted barnacles: an octasphere (six valence-4 vertices on the axes, valence 6 elsewhere) with a
// single-vertex configuration at each of the six axis vertices and double-vertex configurations at valence-6
// vertices far from them and from each other.
TriMesh barnacle_sphere(std::size_t& singles, std::size_t& doubles) {
    TriMesh m = make_octasphere(4);
    const std::size_t base = m.num_vertices();
    const MeshAdjacency adj = build_adjacency(m, 1);
    std::vector<int32_t> axis, picks;
    for (int32_t v = 0; v < static_cast<int32_t>(base); ++v)
        if (adj.valence(v) == 4) axis.push_back(v);
    // Valence-6 vertices whose position is near the diagonal directions (+-1, +-1, +-1)/sqrt(3): far from the axes.
    for (int32_t v = 0; v < static_cast<int32_t>(base); ++v) {
        const V3 p = vertex_of(m, v);
        if (adj.valence(v) != 6) continue;
        const double s = std::fabs(p[0]) + std::fabs(p[1]) + std::fabs(p[2]);
        bool far = s > 1.70;
        for (int32_t q : picks) {
            const V3 o = vertex_of(m, q);
            far = far && (p[0] - o[0]) * (p[0] - o[0]) + (p[1] - o[1]) * (p[1] - o[1]) + (p[2] - o[2]) * (p[2] - o[2]) > 0.5;
        }
        if (far) picks.push_back(v);
    }
    for (int32_t v : axis) insert_single_configuration(m, v);
    for (int32_t v : picks) insert_double_configuration(m, v);
    singles = axis.size();
    doubles = picks.size();
    return m;
}

void add_index_attribute(TriMesh& m) {
    Attribute id{"id", 1, {}};
    for (std::size_t v = 0; v < m.num_vertices(); ++v) id.values.push_back(static_cast<float>(v));
    m.attributes.push_back(id);
}

}  // namespace

// ---- adjacency -------------------------------------------------------------------------------------------------

TEST_CASE("adjacency: one-rings, edges and their triangles", "[post]") {
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
    const EdgeMap edges = build_edge_map(adj, 2);
    CHECK(edges.num_edges() == 3 * m.num_triangles() / 2);
    for (std::size_t e = 0; e < edges.num_edges(); ++e) {
        const int32_t a = edges.edge_vertices[2 * e], b = edges.edge_vertices[2 * e + 1];
        CHECK(a < b);
        CHECK(edges.edge_triangles.size(e) == 2);
        CHECK(find_edge(edges, b, a) == static_cast<int64_t>(e));
    }
    CHECK(find_edge(edges, 0, 0) == -1);
    // Built the same way for any thread count.
    const MeshAdjacency one = build_adjacency(m, 1);
    CHECK(one.vertex_triangles.items == adj.vertex_triangles.items);
    CHECK(one.vertex_neighbours.items == adj.vertex_neighbours.items);
}

// ---- check_mesh ------------------------------------------------------------------------------------------------

TEST_CASE("check_mesh accepts closed oriented manifolds", "[post]") {
    for (const TriMesh& m : {make_icosphere(2), make_cube(), make_torus(2.0, 0.5, 24, 12), make_octasphere(1)}) {
        const MeshCheck c = check_mesh(m);
        CHECK(c.ok());
        CHECK(c.unreferenced_vertices == 0);
        CHECK(c.summary() == "closed, manifold, oriented");
    }
}

TEST_CASE("check_mesh finds a hole", "[post]") {
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

TEST_CASE("check_mesh finds a flipped triangle", "[post]") {
    TriMesh m = make_icosphere(1);
    std::swap(m.triangles[4], m.triangles[5]);
    const MeshCheck c = check_mesh(m);
    CHECK(c.inconsistent_edges == 3);
    CHECK(c.closed());
    CHECK_FALSE(c.oriented());
    CHECK_FALSE(c.ok());
}

TEST_CASE("check_mesh finds a non-manifold edge", "[post]") {
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

TEST_CASE("check_mesh finds a bow-tie vertex", "[post]") {
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

TEST_CASE("check_mesh finds degenerate triangles, non-finite and unreferenced vertices", "[post]") {
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

TEST_CASE("post-processing refuses out-of-range indices", "[post]") {
    TriMesh m = make_cube();
    m.triangles[5] = 42;
    CHECK_THROWS_AS(check_mesh(m), InputError);
    CHECK_THROWS_AS(decimate_barnacles(m, 1), InputError);
    CHECK_THROWS_AS(laplacian_smooth(m, {}, 1, 0.5, 1), InputError);
    TriMesh n = make_cube();
    CHECK_THROWS_AS(laplacian_smooth(n, std::vector<float>(3, 1.0f), 1, 0.5, 1), InputError);
    CHECK_THROWS_AS(mesh_cleanup(n, 0.0, -1.0, 1), InputError);
}

// ---- quality ---------------------------------------------------------------------------------------------------

TEST_CASE("icosphere volume and area approach the sphere's", "[post]") {
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

TEST_CASE("components are found and sorted by signed volume", "[post]") {
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

TEST_CASE("quality report: valences, normal angles, bumpiness", "[post]") {
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

// ---- smoothing -------------------------------------------------------------------------------------------------

TEST_CASE("Laplacian smoothing removes noise", "[post]") {
    TriMesh m = make_noisy_sphere(4, 1.0, 0.03, 7);
    const double before = assess_quality(m).bumpiness;
    laplacian_smooth(m, {}, 10, 0.5, 2);
    const MeshQuality after = assess_quality(m);
    CHECK(after.bumpiness < 0.5 * before);
    CHECK(after.check.ok());
    CHECK(all_finite(m.vertices));
}

TEST_CASE("Laplacian smoothing keeps zero-weight vertices in place", "[post]") {
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

TEST_CASE("Laplacian smoothing is bit-identical for 1 and 2 threads", "[post]") {
    TriMesh a = make_noisy_sphere(4, 1.0, 0.03, 11);
    TriMesh b = a;
    std::vector<float> weights(a.num_vertices());
    for (std::size_t i = 0; i < weights.size(); ++i) weights[i] = static_cast<float>((i * 37) % 101) / 100.0f;
    laplacian_smooth(a, weights, 20, 0.8, 1);
    laplacian_smooth(b, weights, 20, 0.8, 2);
    CHECK(a.vertices == b.vertices);
}

// ---- normals ---------------------------------------------------------------------------------------------------

TEST_CASE("area-weighted normals of a sphere point outward", "[post]") {
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

TEST_CASE("normals never become NaN", "[post]") {
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

TEST_CASE("normal smoothing is bit-identical for 1 and 2 threads", "[post]") {
    TriMesh a = make_noisy_sphere(4, 1.0, 0.03, 5);
    compute_area_weighted_normals(a, 1);
    TriMesh b = a;
    smooth_normals(a, 7, 1);
    smooth_normals(b, 7, 2);
    CHECK(a.normals == b.normals);
}

// ---- decimation ------------------------------------------------------------------------------------------------

TEST_CASE("planted barnacles are detected", "[post]") {
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

TEST_CASE("decimation removes all barnacles and keeps the mesh valid", "[post]") {
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

TEST_CASE("decimation is independent of the thread count", "[post]") {
    std::size_t singles = 0, doubles = 0;
    TriMesh a = barnacle_sphere(singles, doubles);
    TriMesh b = a;
    decimate_barnacles(a, 1);
    decimate_barnacles(b, 2);
    CHECK(a.vertices == b.vertices);
    CHECK(a.triangles == b.triangles);
}

TEST_CASE("decimation handles neighbouring barnacles", "[post]") {
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

TEST_CASE("decimation of a marching-tetrahedra mesh keeps it valid", "[post]") {
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

TEST_CASE("decimation does not crash on broken input", "[post]") {
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

// ---- cleanup ---------------------------------------------------------------------------------------------------

TEST_CASE("mesh cleanup merges vertices sharing a lattice point", "[post]") {
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

TEST_CASE("decimation hands over the adjacency of the mesh it leaves", "[post]") {
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
