// Indexed triangle mesh with shared vertices, as produced by the reconstruction and changed in place by the
// post-processing stages.
#pragma once
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "base/attributes.h"

namespace meniscus {

struct TriMesh {
    std::vector<float> vertices;        // 3 * V
    std::vector<int32_t> triangles;     // 3 * F, counter-clockwise seen from outside the fluid
    std::vector<float> normals;         // 3 * V (unit, outward) or empty
    std::vector<Attribute> attributes;  // per vertex, each count() == num_vertices()
    // Quads (4 vertices each, same winding), made only by the last stage when asked for (post/quads.h); every stage
    // before it works on triangles.
    std::vector<int32_t> quads;

    std::size_t num_vertices() const { return vertices.size() / 3; }
    std::size_t num_triangles() const { return triangles.size() / 3; }
    std::size_t num_quads() const { return quads.size() / 4; }
};

// Triangle t (3 vertex indices) uses one vertex twice: it has no area and no well-defined edges.
inline bool has_repeated_index(const int32_t* t) { return t[0] == t[1] || t[1] == t[2] || t[2] == t[0]; }
// The corner (0, 1 or 2) at which triangle t uses vertex v, which it must contain.
inline int corner_of(const int32_t* t, int32_t v) { return t[0] == v ? 0 : t[1] == v ? 1 : 2; }

// Throws InputError (naming `where`) when array sizes are not multiples of 3, an index is out of range, normals
// are neither empty nor one per vertex, or an attribute does not hold one value tuple per vertex. Every public
// mesh algorithm calls it before touching the arrays.
// The index check runs on `threads` threads (a pass over every index: ~15 M at a million particles).
void validate_mesh_arrays(const TriMesh& mesh, const std::string& where, int threads = 1);

// Position of the first of `indices` outside [0, vertex_count), or indices.size() when all are inside; counted in
// parallel, the first one found serially (only when there is one).
std::size_t first_index_out_of_range(const std::vector<int32_t>& indices, std::size_t vertex_count, int threads);

// Index of the first value that is NaN or infinite, or values.size() when all are finite.
std::size_t first_non_finite(const std::vector<float>& values);

// The mesh with every quad split back into two triangles along its first diagonal (for checks and for formats or
// tools that take triangles only).
TriMesh triangulated(const TriMesh& mesh);

}  // namespace meniscus
