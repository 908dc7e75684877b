#include "mesh/mesh.h"

#include <cmath>
#include <limits>

#include "base/errors.h"
#include "base/parallel.h"

namespace meniscus {

std::size_t first_index_out_of_range(const std::vector<int32_t>& indices, std::size_t vertex_count, int threads) {
    auto outside = [&](std::size_t i) { return indices[i] < 0 || static_cast<std::size_t>(indices[i]) >= vertex_count; };
    const std::size_t count = parallel_count(static_cast<int64_t>(indices.size()), threads, [&](int64_t i) { return outside(static_cast<std::size_t>(i)); });
    if (count == 0) return indices.size();
    std::size_t first = 0;
    while (!outside(first)) ++first;
    return first;
}

void validate_mesh_arrays(const TriMesh& mesh, const std::string& where, int threads) {
    if (mesh.vertices.size() % 3 != 0)
        throw InputError(where + ": vertices must hold 3 floats per vertex, got " + std::to_string(mesh.vertices.size()));
    if (mesh.triangles.size() % 3 != 0)
        throw InputError(where + ": triangles must hold 3 indices per triangle, got " +
                         std::to_string(mesh.triangles.size()));
    const std::size_t nv = mesh.num_vertices();
    if (nv > static_cast<std::size_t>(std::numeric_limits<int32_t>::max()))
        throw InputError(where + ": too many vertices for 32-bit indices (" + std::to_string(nv) + ")");
    const std::size_t i = first_index_out_of_range(mesh.triangles, nv, threads);
    if (i < mesh.triangles.size())
        throw InputError(where + ": triangle " + std::to_string(i / 3) + " uses vertex index " + std::to_string(mesh.triangles[i]) +
                         " but the mesh has " + std::to_string(nv) + " vertices");
    if (!mesh.normals.empty() && mesh.normals.size() != mesh.vertices.size())
        throw InputError(where + ": normals must be empty or 3 floats per vertex, got " + std::to_string(mesh.normals.size()) +
                         " for " + std::to_string(nv) + " vertices");
    require_one_tuple_per_element(mesh.attributes, nv, where, "vertex");
}

std::size_t first_non_finite(const std::vector<float>& values) {
    for (std::size_t i = 0; i < values.size(); ++i)
        if (!std::isfinite(values[i])) return i;
    return values.size();
}

TriMesh triangulated(const TriMesh& mesh) {
    TriMesh out = mesh;
    out.quads.clear();
    for (std::size_t q = 0; q + 3 < mesh.quads.size(); q += 4) {
        const int32_t* v = &mesh.quads[q];
        out.triangles.insert(out.triangles.end(), {v[0], v[1], v[2], v[0], v[2], v[3]});
    }
    return out;
}

}  // namespace meniscus
