// A triangle (and quad) mesh in the layout Blender's Mesh stores, so that a host writes it with plain buffer
// copies: face corners (loops) with their vertices, each face's first corner (offsets, `loop_start`), the edges and
// each corner's edge (`.corner_edge`: the edge from the corner's vertex to the next corner's in its face).
#pragma once
#include <cstdint>
#include <vector>

namespace meniscus {

struct BlenderMeshArrays {
    // The triangles' corners, then the quads'; empty without quads (the corners are then the triangles' indices).
    std::vector<int32_t> corner_vertices;
    std::vector<int32_t> face_offsets;     // first corner of each face: 0, 3, 6, ... then steps of 4 for the quads
    // Distinct edges as (low, high) vertex pairs, numbered in ascending (low, high) order, and each corner's edge.
    // Both empty when has_edges is false: a face repeats a vertex, an edge Blender leaves out (the host lets
    // Blender work out such a mesh's edges).
    std::vector<int32_t> edges;
    std::vector<int32_t> corner_edges;
    bool has_edges = false;
};

// triangles: 3 * triangle_count indices, quads: 4 * quad_count (may be null when quad_count is 0), each index in
// [0, vertex_count), and at most INT32_MAX corners (InputError otherwise). The same arrays at any thread count.
BlenderMeshArrays blender_mesh_arrays(const int32_t* triangles, int64_t triangle_count, const int32_t* quads,
                                      int64_t quad_count, int64_t vertex_count, int threads);

}  // namespace meniscus
