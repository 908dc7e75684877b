// Triangle pairs into quads (post/quads.h).
#include <catch2/catch.hpp>
#include <cmath>

#include "io/io.h"
#include "mesh/topology.h"
#include "post/quads.h"
#include "reader_checks.h"

using namespace meniscus;

namespace {

// A flat n x n grid of unit squares in z = 0, each split into two triangles along a diagonal, wound counter-clockwise
// seen from +z; optionally the vertices with odd x and even y lifted by `bump`: every square then has one lifted
// corner, which folds it along its diagonal.
TriMesh grid(int n, float bump = 0.0f) {
    TriMesh mesh;
    for (int y = 0; y <= n; ++y)
        for (int x = 0; x <= n; ++x) mesh.vertices.insert(mesh.vertices.end(), {float(x), float(y), (x % 2 == 1 && y % 2 == 0) ? bump : 0.0f});
    auto id = [n](int x, int y) { return static_cast<int32_t>(y * (n + 1) + x); };
    for (int y = 0; y < n; ++y)
        for (int x = 0; x < n; ++x) {
            mesh.triangles.insert(mesh.triangles.end(), {id(x, y), id(x + 1, y), id(x + 1, y + 1)});
            mesh.triangles.insert(mesh.triangles.end(), {id(x, y), id(x + 1, y + 1), id(x, y + 1)});
        }
    return mesh;
}

double area(const TriMesh& mesh) {
    double total = 0.0;
    for (std::size_t t = 0; t < mesh.num_triangles(); ++t) {
        const float* a = &mesh.vertices[3 * mesh.triangles[3 * t]];
        const float* b = &mesh.vertices[3 * mesh.triangles[3 * t + 1]];
        const float* c = &mesh.vertices[3 * mesh.triangles[3 * t + 2]];
        const double u[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]}, v[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
        const double n[3] = {u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]};
        total += 0.5 * std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    }
    return total;
}

}  // namespace

TEST_CASE("a flat grid of split squares becomes one quad per square, outward", "[quads]") {
    TriMesh mesh = grid(6);
    const double before = area(mesh);
    REQUIRE(merge_triangles_into_quads(mesh, QuadCriteria{}, 2) == 36);
    REQUIRE(mesh.num_triangles() == 0);
    REQUIRE(mesh.num_quads() == 36);
    for (std::size_t q = 0; q < mesh.num_quads(); ++q) {
        // The diagonal of each square was the shared edge: its quad has four distinct corners of one unit square.
        const int32_t* v = &mesh.quads[4 * q];
        const float* p[4] = {&mesh.vertices[3 * v[0]], &mesh.vertices[3 * v[1]], &mesh.vertices[3 * v[2]], &mesh.vertices[3 * v[3]]};
        // Counter-clockwise seen from +z, like the triangles: positive signed area.
        double signed_area = 0.0;
        for (int k = 0; k < 4; ++k) signed_area += p[k][0] * p[(k + 1) % 4][1] - p[(k + 1) % 4][0] * p[k][1];
        REQUIRE(signed_area == Approx(2.0));
    }
    REQUIRE(area(triangulated(mesh)) == Approx(before));
}

TEST_CASE("folded or stretched pairs stay triangles", "[quads]") {
    TriMesh folded = grid(4, 0.5f);  // every square's two triangles meet at 27 to 37 degrees
    REQUIRE(merge_triangles_into_quads(folded, QuadCriteria{}, 1) == 0);
    QuadCriteria lenient;
    lenient.max_normal_angle = 60.0;
    TriMesh again = grid(4, 0.5f);
    REQUIRE(merge_triangles_into_quads(again, lenient, 1) == 16);

    TriMesh stretched = grid(3);
    for (std::size_t v = 0; v < stretched.num_vertices(); ++v) stretched.vertices[3 * v] *= 4.0f;  // 4:1 rectangles
    REQUIRE(merge_triangles_into_quads(stretched, QuadCriteria{}, 1) == 0);  // edge / diagonal 0.24, below 1 / 1.75
}

TEST_CASE("quads are the same for any thread count", "[quads]") {
    TriMesh one = grid(20, 0.05f), two = grid(20, 0.05f);
    merge_triangles_into_quads(one, QuadCriteria{}, 1);
    merge_triangles_into_quads(two, QuadCriteria{}, 2);
    REQUIRE(one.quads == two.quads);
    REQUIRE(one.triangles == two.triangles);
}

TEST_CASE("quad meshes are written as PLY, OBJ and VTK faces of four corners and checked as closed", "[quads][io]") {
    TriMesh mesh = grid(4);
    merge_triangles_into_quads(mesh, QuadCriteria{}, 1);
    REQUIRE(mesh.num_quads() == 16);
    REQUIRE(mesh.num_triangles() == 0);
    test::TempDir dir("quads");
    for (const char* name : {"grid.ply", "grid.obj", "grid.vtk"}) {
        const std::string path = dir.file(name);
        write_mesh(mesh, path);
        // The readers fan polygons into triangles: a quad comes back as its two halves, its corners in order.
        test::require_same_mesh(triangulated(mesh), read_mesh(path), false);
    }
    // check_mesh judges a quad mesh by its triangulation: the open grid has a boundary, the quads no inner holes.
    const MeshCheck quads = check_mesh(mesh), triangles = check_mesh(triangulated(mesh));
    CHECK(quads.summary() == triangles.summary());
    TriMesh broken = mesh;
    broken.quads[5] = 1000;
    REQUIRE_THROWS_WITH(write_mesh(broken, dir.file("broken.ply")), Catch::Contains("quad 1 refers to vertex 1000"));
}
