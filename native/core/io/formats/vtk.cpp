// Legacy VTK particles (the points and their POINT_DATA of any legacy file, parsed by vtk_legacy.cpp), and meshes written as binary POLYDATA: POINTS, POLYGONS triangles, and
// POINT_DATA with the normals as NORMALS, 1- and 3-component attributes as SCALARS / VECTORS and other component
// counts in a FIELD block (so every attribute reads back as float; whole-number ones are not marked as such).
#include "io/formats/vtk_legacy.h"
#include "io/mesh_writer.h"

namespace meniscus {
namespace io_detail {

ParticleData read_vtk_particles(const Source& source) {
    vtk_legacy::Dataset dataset = vtk_legacy::read(source);
    ParticleData out;
    out.positions = std::move(dataset.positions);
    for (auto& array : dataset.point_data) out.attributes.push_back(std::move(array.attribute));
    return out;
}

void write_vtk_mesh(const TriMesh& mesh, const std::string& path) {
    const std::size_t nv = mesh.num_vertices(), nt = mesh.num_triangles();
    FileWriter out(path);
    out.put("# vtk DataFile Version 4.2\nmeniscus surface mesh\nBINARY\nDATASET POLYDATA\nPOINTS " + std::to_string(nv) +
            " float\n");
    for (float x : mesh.vertices) out.put_be_float(x);
    out.put("\nPOLYGONS " + std::to_string(nt) + " " + std::to_string(4 * nt) + "\n");
    for (std::size_t t = 0; t < nt; ++t) {
        out.put_be32(3);
        for (int k = 0; k < 3; ++k) out.put_be32(static_cast<std::uint32_t>(mesh.triangles[3 * t + k]));
    }
    out.put("\n");
    if (mesh.normals.empty() && mesh.attributes.empty()) {
        out.close();
        return;
    }
    out.put("POINT_DATA " + std::to_string(nv) + "\n");
    auto put_values = [&](const std::vector<float>& values) {
        for (float x : values) out.put_be_float(x);
        out.put("\n");
    };
    if (!mesh.normals.empty()) {
        out.put("NORMALS normals float\n");
        put_values(mesh.normals);
    }
    std::vector<std::size_t> other;  // component counts SCALARS / VECTORS cannot express go to a FIELD block
    for (std::size_t i = 0; i < mesh.attributes.size(); ++i) {
        const auto& a = mesh.attributes[i];
        std::string name = safe_attribute_name(a.name, i);
        if (a.components == 1) {
            out.put("SCALARS " + name + " float 1\nLOOKUP_TABLE default\n");
            put_values(a.values);
        } else if (a.components == 3) {
            out.put("VECTORS " + name + " float\n");
            put_values(a.values);
        } else {
            other.push_back(i);
        }
    }
    if (!other.empty()) {
        out.put("FIELD FieldData " + std::to_string(other.size()) + "\n");
        for (std::size_t i : other) {
            const auto& a = mesh.attributes[i];
            out.put(safe_attribute_name(a.name, i) + " " + std::to_string(a.components) + " " + std::to_string(nv) + " float\n");
            put_values(a.values);
        }
    }
    out.close();
}

}  // namespace io_detail
}  // namespace meniscus
