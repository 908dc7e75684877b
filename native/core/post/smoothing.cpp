#include "post/smoothing.h"

#include <cmath>
#include <string>

#include "base/errors.h"
#include "base/parallel.h"

namespace meniscus {

void umbrella_step(const CsrList& neighbours, const float* in, float* out, const float* weights, double factor, int threads) {
    constexpr int64_t kBlock = 4096;
    const int64_t nv = static_cast<int64_t>(neighbours.rows());
    const float scale = static_cast<float>(factor);
    parallel_blocks(nv, threads, kBlock, [&](int64_t begin, int64_t end) {
        for (int64_t i = begin; i < end; ++i) {
            const int32_t* row = neighbours.row(i);
            const int32_t n = neighbours.size(i);
            const float* xi = in + 3 * i;
            float* yi = out + 3 * i;
            if (n == 0) {
                yi[0] = xi[0], yi[1] = xi[1], yi[2] = xi[2];
                continue;
            }
            // Sum of the offsets to the neighbours: small numbers, so float keeps them accurate wherever the mesh
            // lies (the absolute coordinates would lose bits far from the origin), and no conversions per neighbour.
            float sx = 0.0f, sy = 0.0f, sz = 0.0f;
            for (int32_t k = 0; k < n; ++k) {
                const float* xj = in + 3 * static_cast<int64_t>(row[k]);
                sx += xj[0] - xi[0], sy += xj[1] - xi[1], sz += xj[2] - xi[2];
            }
            // uniform weights w_ij = 1 / |V_i| (Eq. 3)
            const float step = (weights ? scale * weights[i] : scale) / static_cast<float>(n);
            yi[0] = xi[0] + step * sx;
            yi[1] = xi[1] + step * sy;
            yi[2] = xi[2] + step * sz;
        }
    });
}

void laplacian_smooth(TriMesh& mesh, const std::vector<float>& weights, int iterations, double beta, int threads) {
    validate_mesh_arrays(mesh, "laplacian_smooth", threads);
    if (iterations <= 0 || mesh.num_vertices() == 0) {
        laplacian_smooth(mesh, MeshAdjacency{}, weights, iterations, beta, threads);
        return;
    }
    laplacian_smooth(mesh, build_adjacency(mesh, threads), weights, iterations, beta, threads);
}

void laplacian_smooth(TriMesh& mesh, const MeshAdjacency& adjacency, const std::vector<float>& weights, int iterations, double beta,
                      int threads, const WallConstraints* walls) {
    validate_mesh_arrays(mesh, "laplacian_smooth", threads);
    const std::size_t nv = mesh.num_vertices();
    if (iterations < 0) throw InputError("laplacian_smooth: iterations must be >= 0, got " + std::to_string(iterations));
    if (!(beta >= 0.0 && beta <= 1.0))
        throw InputError("laplacian_smooth: beta must be in [0, 1], got " + std::to_string(beta));
    if (!weights.empty() && weights.size() != nv)
        throw InputError("laplacian_smooth: got " + std::to_string(weights.size()) + " weights for " + std::to_string(nv) +
                         " vertices");
    if (iterations == 0 || nv == 0 || beta == 0.0) return;
    const std::size_t non_finite = first_non_finite(mesh.vertices);
    if (non_finite < mesh.vertices.size())
        throw InputError("laplacian_smooth: vertex " + std::to_string(non_finite / 3) + " has a non-finite coordinate");

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
    require_row_per_vertex(neighbours, nv, "laplacian_smooth");
    // Jacobi: every vertex reads the previous iterate only, so the result is independent of the vertex order and
    // of the thread count (bit for bit: each vertex's arithmetic is the same sequence of operations).
    std::vector<float> other(mesh.vertices.size());
    for (int it = 0; it < iterations; ++it) {
        umbrella_step(neighbours, mesh.vertices.data(), other.data(), w, beta, threads);
        mesh.vertices.swap(other);
        if (walls) walls->apply(mesh.vertices.data(), nv);
    }
}

}  // namespace meniscus
