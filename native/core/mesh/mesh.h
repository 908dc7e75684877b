// Indexed triangle mesh with shared vertices, as produced by the reconstruction and changed in place by the
// post-processing stages.
#pragma once
#include <cstddef>
#include <cstdint>
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

}  // namespace meniscus
