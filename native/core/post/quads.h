// Triangle pairs merged into quads, for artists who subdivide the surface (splashsurf's --generate-quads): two
// triangles sharing an edge become one quad when they are nearly coplanar and the quad is nearly rectangular. The
// last stage of the pipeline: normals and attributes are per vertex and do not change.
#pragma once
#include <cstddef>

#include "mesh/mesh.h"

namespace meniscus {

struct QuadCriteria {
    double max_edge_diagonal_ratio = 1.75;  // every edge / diagonal ratio within [1/this, this]
    double max_normal_angle = 10.0;         // degrees between the two triangles' normals
    double max_interior_angle = 135.0;      // degrees, at each of the quad's four corners
};

// Moves the merged triangles of the mesh into mesh.quads (4 vertices each, in the triangles' winding: outward) and
// returns how many quads were made. Candidates are taken best first (the quad's corners closest to right angles),
// ties by edge, so the result is the same for any thread count. Edges that are not shared by exactly two triangles,
// and triangles with a repeated vertex, are left alone.
std::size_t merge_triangles_into_quads(TriMesh& mesh, const QuadCriteria& criteria, int threads);


}  // namespace meniscus
