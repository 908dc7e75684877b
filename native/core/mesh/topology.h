// The consistency check every mesh algorithm is tested against: closed, 2-manifold (edges and vertex fans),
// consistently oriented, no degenerate triangles, finite coordinates.
#pragma once
#include <cstddef>
#include <cstdint>
#include <string>

#include "mesh/mesh.h"

namespace meniscus {

struct MeshCheck {
    std::size_t boundary_edges = 0;          // edges with one incident triangle
    std::size_t non_manifold_edges = 0;      // edges with more than two incident triangles
    std::size_t non_manifold_vertices = 0;   // vertices whose triangle fan is not a single disk
    std::size_t inconsistent_edges = 0;      // edges traversed in the same direction by both triangles
    std::size_t degenerate_triangles = 0;    // repeated vertex index or zero area
    std::size_t non_finite_vertices = 0;     // NaN or Inf coordinate
    std::size_t unreferenced_vertices = 0;
    bool closed() const { return boundary_edges == 0; }
    bool manifold() const { return non_manifold_edges == 0 && non_manifold_vertices == 0; }
    bool oriented() const { return inconsistent_edges == 0; }
    bool ok() const { return closed() && manifold() && oriented() && degenerate_triangles == 0 && non_finite_vertices == 0; }
    std::string summary() const;  // "closed, manifold, oriented" or what is wrong with counts
};

MeshCheck check_mesh(const TriMesh& mesh);

// Exactly zero area (cross product of the edges, in double, is the zero vector): the check's criterion, and the
// collapse guard's after smoothing.
bool triangle_has_zero_area(const float* vertices, const int32_t* triangle);

}  // namespace meniscus
