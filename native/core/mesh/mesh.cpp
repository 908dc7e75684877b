#include "mesh/mesh.h"

#include <cmath>
#include <limits>

#include "base/errors.h"

namespace meniscus {

void validate_mesh_arrays(const TriMesh& mesh, const std::string& where) {
    if (mesh.vertices.size() % 3 != 0)
        throw InputError(where + ": vertices must hold 3 floats per vertex, got " + std::to_string(mesh.vertices.size()));
    if (mesh.triangles.size() % 3 != 0)
        throw InputError(where + ": triangles must hold 3 indices per triangle, got " +
                         std::to_string(mesh.triangles.size()));
    const std::size_t nv = mesh.num_vertices();
    if (nv > static_cast<std::size_t>(std::numeric_limits<int32_t>::max()))
        throw InputError(where + ": too many vertices for 32-bit indices (" + std::to_string(nv) + ")");
    const int32_t* t = mesh.triangles.data();
    const std::size_t n = mesh.triangles.size();
    for (std::size_t i = 0; i < n; ++i)
        if (t[i] < 0 || static_cast<std::size_t>(t[i]) >= nv)
            throw InputError(where + ": triangle " + std::to_string(i / 3) + " uses vertex index " + std::to_string(t[i]) +
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
