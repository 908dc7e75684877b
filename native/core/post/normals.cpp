#include "post/normals.h"

#include <algorithm>
#include <cmath>
#include <string>

#include "base/errors.h"
#include "base/parallel.h"
#include "base/uninitialized_vector.h"
#include "mesh/geometry.h"

namespace meniscus {

namespace {

constexpr int64_t kBlock = 4096;

// Used where no direction can be derived (unreferenced vertex, only degenerate triangles): a unit vector rather
// than zero so that renderers normalising it never divide by zero.
constexpr float kFallback[3] = {0.0f, 0.0f, 1.0f};

bool normalise_into(Vec3d n, float* out) {
    const double length = std::sqrt(dot(n, n));
    if (!(length > 0.0) || !std::isfinite(length)) return false;
    const double inverse = 1.0 / length;  // one division instead of three: this runs per vertex and iteration
    const float r[3] = {static_cast<float>(n.x * inverse), static_cast<float>(n.y * inverse), static_cast<float>(n.z * inverse)};
    if (!std::isfinite(r[0]) || !std::isfinite(r[1]) || !std::isfinite(r[2])) return false;
    out[0] = r[0], out[1] = r[1], out[2] = r[2];
    return true;
}

void set_fallback(float* out) { out[0] = kFallback[0], out[1] = kFallback[1], out[2] = kFallback[2]; }

}  // namespace

std::vector<float> area_weighted_normals(const TriMesh& mesh, const CsrList& vt, int threads) {
    require_row_per_vertex(vt, mesh.num_vertices(), "compute_area_weighted_normals");
    std::vector<float> normals(mesh.vertices.size());
    parallel_blocks(static_cast<int64_t>(mesh.num_vertices()), threads, kBlock, [&](int64_t begin, int64_t end) {
        for (int64_t v = begin; v < end; ++v) {
            // Summing unnormalised cross products is the area-weighted mean direction.
            double sum[3] = {0.0, 0.0, 0.0}, largest[3] = {0.0, 0.0, 0.0}, largest_norm = 0.0;
            for (int64_t k = vt.begin(v); k < vt.end(v); ++k) {
                const Vec3d n = triangle_cross(mesh.vertices.data(), mesh.triangles.data() + 3 * static_cast<int64_t>(vt.items[k]));
                const double norm = dot(n, n);
                if (!std::isfinite(norm)) continue;  // a non-finite neighbour must not poison this vertex
                sum[0] += n.x, sum[1] += n.y, sum[2] += n.z;
                if (norm > largest_norm) largest_norm = norm, largest[0] = n.x, largest[1] = n.y, largest[2] = n.z;
            }
            float* out = normals.data() + 3 * v;
            // Opposite faces can cancel (a thin sheet folded onto itself): fall back to the largest incident face.
            if (!normalise_into({sum[0], sum[1], sum[2]}, out) && !normalise_into({largest[0], largest[1], largest[2]}, out)) set_fallback(out);
        }
    });
    return normals;
}

void smooth_normals(std::vector<float>& normals, const CsrList& neighbours, int iterations, int threads) {
    if (iterations < 0) throw InputError("smooth_normals: iterations must be >= 0, got " + std::to_string(iterations));
    if (iterations == 0) return;
    const int64_t nv = static_cast<int64_t>(normals.size() / 3);
    require_row_per_vertex(neighbours, static_cast<std::size_t>(nv), "smooth_normals");
    // The iterations alternate between the normals and a buffer that the threads touch first (a std::vector would be
    // zero-filled on this thread: ~8 ms at a million vertices); an odd count ends with a parallel copy back.
    UninitializedVector<float> other(normals.size());
    for (int it = 0; it < iterations; ++it) {
        const float* in = it % 2 == 0 ? normals.data() : other.data();
        float* out = it % 2 == 0 ? other.data() : normals.data();
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
                if (!normalise_into(to_vec3d(in + 3 * i), o)) set_fallback(o);
            }
        });
    }
    if (iterations % 2 == 1)
        parallel_blocks(static_cast<int64_t>(normals.size()), threads, int64_t{1} << 16,
                        [&](int64_t begin, int64_t end) { std::copy(other.data() + begin, other.data() + end, normals.data() + begin); });
}

std::vector<float> smoothed_vertex_normals(const TriMesh& mesh, const MeshAdjacency& adjacency, int iterations,
                                           SmoothedNormals computed, int threads) {
    if (computed.iterations == iterations && computed.values.size() == mesh.vertices.size()) return std::move(computed.values);
    std::vector<float> normals = area_weighted_normals(mesh, adjacency.vertex_triangles, threads);
    smooth_normals(normals, adjacency.vertex_neighbours, iterations, threads);
    return normals;
}

void compute_area_weighted_normals(TriMesh& mesh, int threads) {
    validate_mesh_arrays(mesh, "compute_area_weighted_normals", threads);
    mesh.normals = area_weighted_normals(mesh, build_vertex_triangles(mesh, threads), threads);
}

void smooth_normals(TriMesh& mesh, int iterations, int threads) {
    validate_mesh_arrays(mesh, "smooth_normals", threads);
    if (iterations < 0) throw InputError("smooth_normals: iterations must be >= 0, got " + std::to_string(iterations));
    if (iterations == 0 && !mesh.normals.empty()) return;
    const MeshAdjacency adjacency = build_adjacency(mesh, threads);
    if (mesh.normals.empty()) mesh.normals = area_weighted_normals(mesh, adjacency.vertex_triangles, threads);
    const std::size_t non_finite = first_non_finite(mesh.normals);
    if (non_finite < mesh.normals.size())
        throw InputError("smooth_normals: normal of vertex " + std::to_string(non_finite / 3) + " is not finite");
    smooth_normals(mesh.normals, adjacency.vertex_neighbours, iterations, threads);
}

}  // namespace meniscus
