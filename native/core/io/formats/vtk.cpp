// Legacy VTK particles (the points and their POINT_DATA of any legacy file) and meshes (POLYDATA: the points, their
// POLYGONS fanned into triangles, the first 3-component NORMALS as the normals and every other POINT_DATA array as an
// attribute), both parsed by vtk_legacy.cpp; and meshes written as binary POLYDATA: POINTS, POLYGONS triangles, and
// POINT_DATA with the normals as NORMALS, 1- and 3-component attributes as SCALARS / VECTORS and other component
// counts in a FIELD block (so every attribute reads back as float; whole-number ones are not marked as such).
#include "io/formats/vtk_legacy.h"
#include "io/mesh_writer.h"

namespace meniscus {
namespace io_detail {

ParticleData read_vtk_particles(const Source& source) {
    vtk_legacy::Dataset dataset = vtk_legacy::read(source, vtk_legacy::Options{});
    ParticleData out;
    out.positions = std::move(dataset.positions);
    for (auto& array : dataset.point_data) out.attributes.push_back(std::move(array.attribute));
    return out;
}

namespace {

// Polygon i's vertices as triangles (a fan around its first vertex), each index checked against the points.
void add_polygon(const Cursor& c, const vtk_legacy::Polygons& polygons, std::size_t i, std::size_t points, std::vector<std::int32_t>& out) {
    const std::uint64_t begin = polygons.offsets[i], end = polygons.offsets[i + 1];
    if (end - begin < 3)
        c.fail("POLYGONS cell " + std::to_string(i) + " has only " + std::to_string(end - begin) + " vertices (a face needs 3)");
    for (std::uint64_t k = begin; k < end; ++k) {
        const std::int64_t v = polygons.connectivity[static_cast<std::size_t>(k)];
        if (v < 0 || static_cast<std::uint64_t>(v) >= points || v > INT32_MAX)
            c.fail("POLYGONS cell " + std::to_string(i) + " refers to vertex " + std::to_string(v) + " but there are only " +
                   std::to_string(points) + " points");
    }
    for (std::uint64_t k = begin + 1; k + 1 < end; ++k)
        for (std::uint64_t corner : {begin, k, k + 1}) out.push_back(static_cast<std::int32_t>(polygons.connectivity[static_cast<std::size_t>(corner)]));
}

// POINT_DATA: the normals (when given) and every attribute, as SCALARS, VECTORS or, for other component counts, a
// FIELD block. Shared by meshes and particles.
void put_point_data(FileWriter& out, std::size_t nv, const std::vector<float>& normals, const std::vector<Attribute>& attributes) {
    if (normals.empty() && attributes.empty()) return;
    out.put("POINT_DATA " + std::to_string(nv) + "\n");
    auto put_values = [&](const std::vector<float>& values) {
        for (float x : values) out.put_be_float(x);
        out.put("\n");
    };
    if (!normals.empty()) {
        out.put("NORMALS normals float\n");
        put_values(normals);
    }
    std::vector<std::size_t> other;  // component counts SCALARS / VECTORS cannot express go to a FIELD block
    for (std::size_t i = 0; i < attributes.size(); ++i) {
        const auto& a = attributes[i];
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
            const auto& a = attributes[i];
            out.put(safe_attribute_name(a.name, i) + " " + std::to_string(a.components) + " " + std::to_string(nv) + " float\n");
            put_values(a.values);
        }
    }
}

}  // namespace

TriMesh read_vtk_mesh(const Source& source) {
    vtk_legacy::Options options;
    options.polygons = true;
    vtk_legacy::Dataset dataset = vtk_legacy::read(source, options);
    const Cursor c(source);
    if (dataset.unstructured_grid)
        c.fail("a legacy VTK mesh must be DATASET POLYDATA with POLYGONS; the cells of an UNSTRUCTURED_GRID are not read as faces");
    // write_mesh always writes POLYGONS (POLYGONS 0 0 for no faces): without it the file was cut short.
    if (!dataset.have_polygons) c.fail("no POLYGONS section: a legacy VTK mesh lists its faces as POLYGONS (file truncated?)");
    TriMesh mesh;
    mesh.vertices = std::move(dataset.positions);
    const vtk_legacy::Polygons& polygons = dataset.polygons;
    for (std::size_t i = 0; i < polygons.count(); ++i) add_polygon(c, polygons, i, mesh.num_vertices(), mesh.triangles);
    for (auto& array : dataset.point_data) {
        if (array.section == "NORMALS" && array.attribute.components == 3 && mesh.normals.empty())
            mesh.normals = std::move(array.attribute.values);
        else
            mesh.attributes.push_back(std::move(array.attribute));
    }
    return mesh;
}

void write_vtk_mesh(const TriMesh& mesh, const std::string& path, int threads) {
    const std::size_t nv = mesh.num_vertices(), nt = mesh.num_triangles();
    FileWriter out(path);
    out.put("# vtk DataFile Version 4.2\nmeniscus surface mesh\nBINARY\nDATASET POLYDATA\nPOINTS " + std::to_string(nv) +
            " float\n");
    out.put_in_parallel(static_cast<int64_t>(mesh.vertices.size()), threads, [&](int64_t begin, int64_t end, Encoder& block) {
        for (int64_t i = begin; i < end; ++i) block.put_be_float(mesh.vertices[i]);
    });
    const std::size_t nq = mesh.num_quads();
    out.put("\nPOLYGONS " + std::to_string(nt + nq) + " " + std::to_string(4 * nt + 5 * nq) + "\n");
    out.put_in_parallel(static_cast<int64_t>(nt), threads, [&](int64_t begin, int64_t end, Encoder& block) {
        for (int64_t t = begin; t < end; ++t) {
            block.put_be32(3);
            for (int k = 0; k < 3; ++k) block.put_be32(static_cast<std::uint32_t>(mesh.triangles[3 * t + k]));
        }
    });
    for (std::size_t q = 0; q < nq; ++q) {
        out.put_be32(4);
        for (int k = 0; k < 4; ++k) out.put_be32(static_cast<std::uint32_t>(mesh.quads[4 * q + k]));
    }
    out.put("\n");
    put_point_data(out, nv, mesh.normals, mesh.attributes);
    out.close();
}

// Particles as splashsurf and ParaView read them: an UNSTRUCTURED_GRID of VERTEX cells (type 1), one per particle.
void write_vtk_particles(const ParticleData& particles, const std::string& path) {
    const std::size_t n = particles.size();
    FileWriter out(path);
    out.put("# vtk DataFile Version 4.2\nmeniscus particles\nBINARY\nDATASET UNSTRUCTURED_GRID\nPOINTS " + std::to_string(n) +
            " float\n");
    for (float x : particles.positions) out.put_be_float(x);
    out.put("\nCELLS " + std::to_string(n) + " " + std::to_string(2 * n) + "\n");
    for (std::size_t i = 0; i < n; ++i) {
        out.put_be32(1);
        out.put_be32(static_cast<std::uint32_t>(i));
    }
    out.put("\nCELL_TYPES " + std::to_string(n) + "\n");
    for (std::size_t i = 0; i < n; ++i) out.put_be32(1);
    out.put("\n");
    put_point_data(out, n, {}, particles.attributes);
    out.close();
}

}  // namespace io_detail
}  // namespace meniscus
