// Vertex normals (paper Sec. 3.4): area-weighted face normals, optionally smoothed by Eq. 12. (The SPH alternative,
// the colour field's gradient, is sph/interpolation.h's colour_field_normals.)
#pragma once
#include <vector>

#include "mesh/adjacency.h"
#include "mesh/mesh.h"

namespace meniscus {

// Unit outward normal per vertex: the sum of the cross products of its triangles (each as long as twice the
// triangle's area), normalised. Where that sum vanishes, the largest incident face's normal; where there is none
// (unreferenced vertex, only zero-area triangles), +z, so that renderers never divide by zero.
std::vector<float> area_weighted_normals(const TriMesh& mesh, const CsrList& vertex_triangles, int threads);

// `iterations` Jacobi steps of Eq. 12 on unit normals (3 per vertex): each becomes the normalised sum of its
// neighbours' normals. The same bits for any thread count.
void smooth_normals(std::vector<float>& normals, const CsrList& vertex_neighbours, int iterations, int threads);

// Normals already computed for a surface: area-weighted, then `iterations` steps of Eq. 12 (volume restoration
// computes them to move the vertices along).
struct SmoothedNormals {
    std::vector<float> values;  // 3 per vertex; empty when there are none
    int iterations = 0;
};

// The normals stage's area-weighted normals smoothed by `iterations` steps of Eq. 12: `computed` itself when it
// holds exactly those for this mesh (same iteration count), otherwise computed anew.
std::vector<float> smoothed_vertex_normals(const TriMesh& mesh, const MeshAdjacency& adjacency, int iterations,
                                           SmoothedNormals computed, int threads);

// On a mesh alone (the adjacency built here): fills mesh.normals with area-weighted normals; smooths mesh.normals
// (computing them first when empty; InputError for a non-finite one).
void compute_area_weighted_normals(TriMesh& mesh, int threads);
void smooth_normals(TriMesh& mesh, int iterations, int threads);

}  // namespace meniscus
