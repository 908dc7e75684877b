// Weighted explicit uniform-Laplacian smoothing (paper Eq. 3-5) with a Jacobi update:
// x_i += beta * w_i * (mean_{j in N(i)} x_j - x_i), w_i in [0, 1] the feature weights (weights.h).
#pragma once
#include <vector>

#include "mesh/adjacency.h"
#include "mesh/mesh.h"
#include "post/wall_constraints.h"

namespace meniscus {

// `iterations` Jacobi steps on mesh.vertices. weights: one per vertex in [0, 1] (clamped; NaN refused); empty means
// 1 everywhere (plain uniform smoothing). The same bits for any thread count. With walls, vertices on a container's
// wall are put back on it after every step: they slide along it.
void laplacian_smooth(TriMesh& mesh, const MeshAdjacency& adjacency, const std::vector<float>& weights, int iterations, double beta,
                      int threads, const WallConstraints* walls = nullptr);
// The same, building the adjacency.
void laplacian_smooth(TriMesh& mesh, const std::vector<float>& weights, int iterations, double beta, int threads);

// One Jacobi step of the uniform umbrella operator on 3-float positions:
// out_i = in_i + factor * w_i * (mean_{j in N(i)} in_j - in_i), with w_i = 1 when weights is null. Vertices
// without neighbours keep their position. Offsets summed in float per vertex, independent of the thread count.
void umbrella_step(const CsrList& neighbours, const float* in, float* out, const float* weights, double factor, int threads);

}  // namespace meniscus
