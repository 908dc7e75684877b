// Vertex normals (paper Sec. 3.4): area-weighted face normals, then optional smoothing by Eq. 12.
#include <cmath>
#include <string>
#include <vector>

#include "base/errors.h"
#include "mesh/adjacency.h"
#include "post/postprocess.h"

namespace meniscus {

namespace {

constexpr int64_t kBlock = 4096;

// Used where no direction can be derived (unreferenced vertex, only degenerate triangles): a unit vector rather
// than zero so that renderers normalising it never divide by zero.
constexpr float kFallback[3] = {0.0f, 0.0f, 1.0f};

void face_cross(const float* v, const int32_t* t, double n[3]) {
    const float* a = v + 3 * static_cast<int64_t>(t[0]);
    const float* b = v + 3 * static_cast<int64_t>(t[1]);
    const float* c = v + 3 * static_cast<int64_t>(t[2]);
    const double e1[3] = {double(b[0]) - a[0], double(b[1]) - a[1], double(b[2]) - a[2]};
    const double e2[3] = {double(c[0]) - a[0], double(c[1]) - a[1], double(c[2]) - a[2]};
    n[0] = e1[1] * e2[2] - e1[2] * e2[1];
    n[1] = e1[2] * e2[0] - e1[0] * e2[2];
    n[2] = e1[0] * e2[1] - e1[1] * e2[0];
}

bool normalise_into(const double n[3], float* out) {
    const double length = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    if (!(length > 0.0) || !std::isfinite(length)) return false;
    const double inverse = 1.0 / length;  // one division instead of three: this runs per vertex and iteration
    const float r[3] = {static_cast<float>(n[0] * inverse), static_cast<float>(n[1] * inverse), static_cast<float>(n[2] * inverse)};
    if (!std::isfinite(r[0]) || !std::isfinite(r[1]) || !std::isfinite(r[2])) return false;
    out[0] = r[0], out[1] = r[1], out[2] = r[2];
    return true;
}

}  // namespace

void compute_area_weighted_normals(TriMesh& mesh, int threads) {
    validate_mesh_arrays(mesh, "compute_area_weighted_normals");
    MeshAdjacency adjacency;
    adjacency.vertex_triangles = build_vertex_triangles(mesh, threads);
    compute_area_weighted_normals(mesh, adjacency, threads);
}

void compute_area_weighted_normals(TriMesh& mesh, const MeshAdjacency& adjacency, int threads) {
    const int64_t nv = static_cast<int64_t>(mesh.num_vertices());
    const CsrList& vt = adjacency.vertex_triangles;
    if (vt.rows() != mesh.num_vertices()) throw InputError("compute_area_weighted_normals: the adjacency does not belong to this mesh");
    std::vector<float> normals(mesh.vertices.size());
    parallel_blocks(nv, threads, kBlock, [&](int64_t begin, int64_t end) {
        for (int64_t v = begin; v < end; ++v) {
            // The cross product's length is twice the triangle's area: summing unnormalised cross products is the
            // area-weighted mean direction.
            double sum[3] = {0.0, 0.0, 0.0}, largest[3] = {0.0, 0.0, 0.0}, largest_norm = 0.0;
            for (int64_t k = vt.begin(v); k < vt.end(v); ++k) {
                double n[3];
                face_cross(mesh.vertices.data(), mesh.triangles.data() + 3 * static_cast<int64_t>(vt.items[k]), n);
                const double norm = n[0] * n[0] + n[1] * n[1] + n[2] * n[2];
                if (!std::isfinite(norm)) continue;  // a non-finite neighbour must not poison this vertex
                sum[0] += n[0], sum[1] += n[1], sum[2] += n[2];
                if (norm > largest_norm) largest_norm = norm, largest[0] = n[0], largest[1] = n[1], largest[2] = n[2];
            }
            float* out = normals.data() + 3 * v;
            // Opposite faces can cancel (a thin sheet folded onto itself): fall back to the largest incident face.
            if (!normalise_into(sum, out) && !normalise_into(largest, out))
                out[0] = kFallback[0], out[1] = kFallback[1], out[2] = kFallback[2];
        }
    });
    mesh.normals.swap(normals);
}

void smooth_normals(TriMesh& mesh, int iterations, int threads) {
    validate_mesh_arrays(mesh, "smooth_normals");
    if (iterations < 0) throw InputError("smooth_normals: iterations must be >= 0, got " + std::to_string(iterations));
    if (iterations == 0 && !mesh.normals.empty()) return;
    smooth_normals(mesh, build_adjacency(mesh, threads), iterations, threads);
}

void smooth_normals(TriMesh& mesh, const MeshAdjacency& adjacency, int iterations, int threads) {
    if (iterations < 0) throw InputError("smooth_normals: iterations must be >= 0, got " + std::to_string(iterations));
    if (mesh.normals.empty()) compute_area_weighted_normals(mesh, adjacency, threads);
    for (std::size_t i = 0; i < mesh.normals.size(); ++i)
        if (!std::isfinite(mesh.normals[i]))
            throw InputError("smooth_normals: normal of vertex " + std::to_string(i / 3) + " is not finite");
    if (iterations == 0) return;
    const int64_t nv = static_cast<int64_t>(mesh.num_vertices());
    const CsrList& neighbours = adjacency.vertex_neighbours;
    if (neighbours.rows() != mesh.num_vertices()) throw InputError("smooth_normals: the adjacency does not belong to this mesh");
    std::vector<float> other(mesh.normals.size());
    for (int it = 0; it < iterations; ++it) {
        const float* in = mesh.normals.data();
        float* out = other.data();
        parallel_blocks(nv, threads, kBlock, [&](int64_t begin, int64_t end) {
            for (int64_t i = begin; i < end; ++i) {
                // Eq. 12 sums over the neighbours j in V_i only, without n_i itself, as the paper and splashsurf
                // do, so results match the reference. This is safe: the mean-of-neighbours operator has an
                // eigenvalue -1 (a checkerboard oscillation that never decays) only on bipartite graphs, and a
                // triangle mesh is never bipartite; n_i is still used as the fallback when the sum cancels.
                // Unit vectors, a handful per vertex: float sums are accurate enough and need no conversions.
                float sum[3] = {0.0f, 0.0f, 0.0f};
                for (int64_t k = neighbours.begin(i); k < neighbours.end(i); ++k) {
                    const float* nj = in + 3 * static_cast<int64_t>(neighbours.items[k]);
                    sum[0] += nj[0], sum[1] += nj[1], sum[2] += nj[2];
                }
                float* o = out + 3 * i;
                const float length_squared = sum[0] * sum[0] + sum[1] * sum[1] + sum[2] * sum[2];
                if (length_squared > 1e-12f && std::isfinite(length_squared)) {
                    const float inverse = 1.0f / std::sqrt(length_squared);
                    o[0] = sum[0] * inverse, o[1] = sum[1] * inverse, o[2] = sum[2] * inverse;
                    continue;
                }
                const double own[3] = {in[3 * i], in[3 * i + 1], in[3 * i + 2]};
                if (!normalise_into(own, o)) o[0] = kFallback[0], o[1] = kFallback[1], o[2] = kFallback[2];
            }
        });
        mesh.normals.swap(other);
    }
}

}  // namespace meniscus
