#include "mesh/blender_arrays.h"

#include <algorithm>
#include <string>

#include "base/errors.h"
#include "base/short_sort.h"

namespace meniscus {

namespace {

// Calls visit(c, a, b) for every corner c in order, with a its vertex and b the next corner's vertex in its face
// (faces of 3 corners, then faces of 4 from quad_start on).
template <class Visit>
void for_each_corner_edge(const int32_t* v, int64_t quad_start, int64_t corner_count, Visit&& visit) {
    for (int64_t c = 0; c < quad_start; c += 3) {
        visit(c, v[c], v[c + 1]);
        visit(c + 1, v[c + 1], v[c + 2]);
        visit(c + 2, v[c + 2], v[c]);
    }
    for (int64_t c = quad_start; c < corner_count; c += 4) {
        visit(c, v[c], v[c + 1]);
        visit(c + 1, v[c + 1], v[c + 2]);
        visit(c + 2, v[c + 2], v[c + 3]);
        visit(c + 3, v[c + 3], v[c]);
    }
}

}  // namespace

BlenderMeshArrays blender_mesh_arrays(const int32_t* triangles, int64_t triangle_count, const int32_t* quads,
                                      int64_t quad_count, int64_t vertex_count, int threads) {
    static_cast<void>(threads);  // serial throughout: each step is a memory-bound pass, and the same at any count
    if (triangle_count < 0 || quad_count < 0 || vertex_count < 0 || vertex_count > INT32_MAX)
        throw InputError("blender_mesh_arrays: negative counts or more vertices than 32-bit indices hold");
    const int64_t quad_start = 3 * triangle_count;
    if (triangle_count > INT32_MAX || quad_count > INT32_MAX || quad_start + 4 * quad_count > INT32_MAX)
        throw InputError("blender_mesh_arrays: " + std::to_string(triangle_count) + " triangles and " +
                         std::to_string(quad_count) + " quads have more face corners than Blender's 32-bit indices hold");
    BlenderMeshArrays out;
    const int64_t corner_count = quad_start + 4 * quad_count;
    // Without quads the corners are the triangles' indices as they are: no copy (the host uses its own array).
    if (quad_count > 0) out.corner_vertices.resize(static_cast<std::size_t>(corner_count));
    int32_t* copy = quad_count > 0 ? out.corner_vertices.data() : nullptr;
    int64_t outside = 0;
    const auto take = [&](const int32_t* indices, int64_t count) {  // the range check, fused with the copy
        for (int64_t i = 0; i < count; ++i) {
            const int32_t v = indices[i];
            outside += v < 0 || v >= vertex_count;
            if (copy != nullptr) *copy++ = v;
        }
    };
    take(triangles, quad_start);
    take(quads, 4 * quad_count);
    if (outside > 0)
        throw InputError("blender_mesh_arrays: " + std::to_string(outside) + " face corners refer to no vertex (there are " +
                         std::to_string(vertex_count) + ")");
    const int32_t* corners = quad_count > 0 ? out.corner_vertices.data() : triangles;

    out.face_offsets.resize(static_cast<std::size_t>(triangle_count + quad_count));
    for (int64_t f = 0; f < triangle_count; ++f) out.face_offsets[static_cast<std::size_t>(f)] = static_cast<int32_t>(3 * f);
    for (int64_t q = 0; q < quad_count; ++q)
        out.face_offsets[static_cast<std::size_t>(triangle_count + q)] = static_cast<int32_t>(quad_start + 4 * q);

    // Each corner's edge seen from its lower vertex: the corners' (higher vertex, corner) keys grouped by the lower
    // vertex (a counting sort), each group sorted, equal higher vertices one edge. Edges are numbered group by group,
    // so in (low, high) order. Serial, so the same at any thread count by construction.
    std::vector<int64_t> group_start(static_cast<std::size_t>(vertex_count) + 1, 0);
    bool repeats_a_vertex = false;
    for_each_corner_edge(corners, quad_start, corner_count, [&](int64_t, int32_t a, int32_t b) {
        repeats_a_vertex |= a == b;
        ++group_start[static_cast<std::size_t>(std::min(a, b)) + 1];
    });
    if (repeats_a_vertex) return out;  // Blender decides what such a face's edges are
    for (std::size_t v = 0; v < static_cast<std::size_t>(vertex_count); ++v) group_start[v + 1] += group_start[v];
    // (higher vertex << 32 | corner): sorting the plain integers orders a group by higher vertex, then by corner.
    std::vector<uint64_t> keys(static_cast<std::size_t>(corner_count));
    {
        std::vector<int64_t> next(group_start.begin(), group_start.end() - 1);
        for_each_corner_edge(corners, quad_start, corner_count, [&](int64_t c, int32_t a, int32_t b) {
            keys[static_cast<std::size_t>(next[static_cast<std::size_t>(std::min(a, b))]++)] =
                static_cast<uint64_t>(std::max(a, b)) << 32 | static_cast<uint64_t>(c);
        });
    }
    out.corner_edges.resize(static_cast<std::size_t>(corner_count));
    out.edges.reserve(static_cast<std::size_t>(corner_count));  // closed surfaces: half as many; trimmed below
    int32_t edge = -1;
    for (std::size_t v = 0; v < static_cast<std::size_t>(vertex_count); ++v) {
        uint64_t* first = keys.data() + group_start[v];
        uint64_t* last = keys.data() + group_start[v + 1];
        if (last - first > 1) sort_short(first, last);  // an empty group may have no storage to point into
        for (uint64_t* key = first; key < last; ++key) {
            const int32_t high = static_cast<int32_t>(*key >> 32);
            if (key == first || high != static_cast<int32_t>(*(key - 1) >> 32)) {
                ++edge;
                out.edges.push_back(static_cast<int32_t>(v));
                out.edges.push_back(high);
            }
            out.corner_edges[static_cast<std::size_t>(*key & 0xffffffffu)] = edge;
        }
    }
    out.edges.shrink_to_fit();
    out.has_edges = true;
    return out;
}

}  // namespace meniscus
