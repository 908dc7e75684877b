// The mesh in Blender's layout (mesh/blender_arrays.h): refusals before any index is read, and the arrays of
// triangles alone (no copy of the corners) against those of the same faces given with an empty quad list.
#include <catch2/catch.hpp>

#include <cstdint>
#include <vector>

#include "base/errors.h"
#include "mesh/blender_arrays.h"

using namespace meniscus;

TEST_CASE("blender_mesh_arrays refuses more corners than 32-bit indices hold", "[blender_arrays]") {
    const int32_t triangle[3] = {0, 1, 2};
    // Refused from the counts alone: the pointers are never read past the first face.
    REQUIRE_THROWS_AS(blender_mesh_arrays(triangle, int64_t{INT32_MAX} / 3 + 1, nullptr, 0, 3, 1), InputError);
    REQUIRE_THROWS_WITH(blender_mesh_arrays(triangle, 1, triangle, int64_t{INT32_MAX} / 4 + 1, 3, 1),
                        Catch::Contains("more face corners than Blender's 32-bit indices hold"));
}

TEST_CASE("blender_mesh_arrays of triangles alone", "[blender_arrays]") {
    // Vertices 4 to 9 are used by no corner: empty groups in the edge sort, the last ones past every key.
    const std::vector<int32_t> triangles = {0, 1, 2, 2, 1, 3};
    for (int threads : {1, 2}) {
        const BlenderMeshArrays arrays = blender_mesh_arrays(triangles.data(), 2, nullptr, 0, 10, threads);
        CHECK(arrays.corner_vertices.empty());  // the triangles' own indices are the corners
        CHECK(arrays.face_offsets == std::vector<int32_t>{0, 3});
        CHECK(arrays.edges == std::vector<int32_t>{0, 1, 0, 2, 1, 2, 1, 3, 2, 3});
        CHECK(arrays.corner_edges == std::vector<int32_t>{0, 2, 1, 2, 3, 4});
    }
    const BlenderMeshArrays none = blender_mesh_arrays(nullptr, 0, nullptr, 0, 3, 1);
    CHECK(none.has_edges);
    CHECK(none.edges.empty());
    CHECK(none.face_offsets.empty());
}
