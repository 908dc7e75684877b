// Weighted explicit uniform-Laplacian smoothing (paper Eq. 3-5).
#include <cmath>
#include <string>
#include <vector>

#include "base/errors.h"
#include "mesh/adjacency.h"
#include "post/postprocess.h"

namespace meniscus {

void laplacian_smooth(TriMesh& mesh, const std::vector<float>& weights, int iterations, double beta, int threads) {
    validate_mesh_arrays(mesh, "laplacian_smooth");
    if (iterations <= 0 || mesh.num_vertices() == 0) {
        laplacian_smooth(mesh, MeshAdjacency{}, weights, iterations, beta, threads);
        return;
    }
    laplacian_smooth(mesh, build_adjacency(mesh, threads), weights, iterations, beta, threads);
}

void laplacian_smooth(TriMesh& mesh, const MeshAdjacency& adjacency, const std::vector<float>& weights, int iterations, double beta,
                      int threads) {
    validate_mesh_arrays(mesh, "laplacian_smooth");
    const std::size_t nv = mesh.num_vertices();
    if (iterations < 0) throw InputError("laplacian_smooth: iterations must be >= 0, got " + std::to_string(iterations));
    if (!(beta >= 0.0 && beta <= 1.0))
        throw InputError("laplacian_smooth: beta must be in [0, 1], got " + std::to_string(beta));
    if (!weights.empty() && weights.size() != nv)
        throw InputError("laplacian_smooth: got " + std::to_string(weights.size()) + " weights for " + std::to_string(nv) +
                         " vertices");
    if (iterations == 0 || nv == 0 || beta == 0.0) return;
    for (std::size_t i = 0; i < mesh.vertices.size(); ++i)
        if (!std::isfinite(mesh.vertices[i]))
            throw InputError("laplacian_smooth: vertex " + std::to_string(i / 3) + " has a non-finite coordinate");

    // Weights are documented as [0, 1]; clamp so that rounding in their computation (a smoothstep of 1.0000001)
    // cannot make a step overshoot, and refuse NaN outright since it would spread through the whole mesh.
    std::vector<float> clamped;
    const float* w = nullptr;
    if (!weights.empty()) {
        clamped.resize(nv);
        for (std::size_t i = 0; i < nv; ++i) {
            if (std::isnan(weights[i]))
                throw InputError("laplacian_smooth: weight of vertex " + std::to_string(i) + " is NaN");
            clamped[i] = std::fmin(1.0f, std::fmax(0.0f, weights[i]));
        }
        w = clamped.data();
    }
    const CsrList& neighbours = adjacency.vertex_neighbours;
    if (neighbours.rows() != nv) throw InputError("laplacian_smooth: the adjacency does not belong to this mesh");
    // Jacobi: every vertex reads the previous iterate only, so the result is independent of the vertex order and
    // of the thread count (bit for bit: each vertex's arithmetic is the same sequence of operations).
    std::vector<float> other(mesh.vertices.size());
    for (int it = 0; it < iterations; ++it) {
        umbrella_step(neighbours, mesh.vertices.data(), other.data(), w, beta, threads);
        mesh.vertices.swap(other);
    }
}

}  // namespace meniscus
