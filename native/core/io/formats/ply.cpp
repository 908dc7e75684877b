// PLY: vertex elements read as particles or meshes (with faces), and meshes written as binary little-endian PLY.
//
// Written vertex properties, all float: x y z; nx ny nz when the mesh has normals; then each attribute in order:
// one component -> NAME, three -> NAME_x NAME_y NAME_z, any other count k -> NAME_0 .. NAME_{k-1} (int instead of
// float for whole-number attributes). Names are made PLY-safe (whitespace and control characters become '_', an empty
// name becomes attribute_<i>, and names that would clash with x y z nx ny nz get an "attr_" prefix). Reading reverses
// this: consecutive NAME_x NAME_y NAME_z properties become one 3-component attribute, consecutive NAME_0 ..
// NAME_{k-1} (k >= 2) one k-component attribute, anything else a scalar. (So scalar attributes that happen to be
// named like "v_x", "v_y", "v_z" come back merged.) Read as particles, nx ny nz and vx vy vz become the attributes
// "normal" and "velocity"; faces and other elements are checked and skipped.
#include <algorithm>
#include <cmath>

#include "io/io_util.h"
#include "io/mesh_writer.h"

namespace meniscus {
namespace io_detail {
namespace {

// ---- reading -------------------------------------------------------------------------------------------------


struct PlyProperty {
    std::string name;
    ScalarType type = ScalarType::f32;
    bool is_list = false;
    ScalarType count_type = ScalarType::u8;
};

struct PlyElement {
    std::string name;
    std::uint64_t count = 0;
    std::vector<PlyProperty> properties;
};

bool ply_type_from_name(std::string_view name, ScalarType& type) {
    static const ScalarTypeName table[] = {
        {"char", ScalarType::i8},    {"int8", ScalarType::i8},     {"uchar", ScalarType::u8},   {"uint8", ScalarType::u8},
        {"short", ScalarType::i16},  {"int16", ScalarType::i16},   {"ushort", ScalarType::u16}, {"uint16", ScalarType::u16},
        {"int", ScalarType::i32},    {"int32", ScalarType::i32},   {"uint", ScalarType::u32},   {"uint32", ScalarType::u32},
        {"float", ScalarType::f32},  {"float32", ScalarType::f32}, {"double", ScalarType::f64}, {"float64", ScalarType::f64},
    };
    return find_scalar_type(table, name, false, type);
}

// Where one vertex property goes: component k of vector `target` (nullptr: discarded).
struct Column {
    std::vector<float>* target = nullptr;
    int components = 1;
    int k = 0;
};

class PlyReader {
public:
    // particles: read the vertex element only as particles (faces and other elements are checked and skipped;
    // nx ny nz stay an attribute "normal" rather than becoming mesh normals).
    explicit PlyReader(const Source& source, bool particles = false) : c_(source), particles_(particles) {}

    TriMesh read() {
        read_header();
        for (const auto& element : elements_) read_element(element);
        if (particles_) {
            if (!have_vertex_element_) c_.fail("no vertex element: a PLY particle file needs 'element vertex N' with x, y, z");
            return std::move(mesh_);
        }
        const std::size_t nv = mesh_.num_vertices();
        for (std::size_t i = 0; i < mesh_.triangles.size(); ++i)
            if (mesh_.triangles[i] < 0 || static_cast<std::size_t>(mesh_.triangles[i]) >= nv)
                c_.fail("face refers to vertex " + std::to_string(mesh_.triangles[i]) + " but there are only " +
                        std::to_string(nv) + " vertices");
        return std::move(mesh_);
    }

private:
    Cursor c_;
    bool particles_ = false;
    bool have_vertex_element_ = false;
    enum class Format { ascii, binary_le, binary_be } format_ = Format::ascii;
    std::vector<PlyElement> elements_;
    TriMesh mesh_;

    void read_header() {
        std::string_view magic = c_.line();
        if (magic != "ply") c_.fail("not a PLY file: the first line is " + quote(magic) + " instead of 'ply'");
        bool have_format = false;
        while (true) {
            if (c_.at_end()) c_.fail("truncated at " + c_.where() + ": the PLY header has no end_header line");
            std::size_t pos = c_.pos();
            auto tokens = split_tokens(c_.line(), 16);
            if (tokens.empty()) continue;
            std::string_view keyword = tokens[0];
            if (keyword == "end_header") break;
            if (keyword == "comment" || keyword == "obj_info") continue;
            if (keyword == "format") {
                if (tokens.size() < 2) c_.fail("format line without a format at " + c_.where(pos));
                if (tokens[1] == "ascii")
                    format_ = Format::ascii;
                else if (tokens[1] == "binary_little_endian")
                    format_ = Format::binary_le;
                else if (tokens[1] == "binary_big_endian")
                    format_ = Format::binary_be;
                else
                    c_.fail("unknown PLY format " + quote(tokens[1]) + " at " + c_.where(pos) +
                            " (expected ascii, binary_little_endian or binary_big_endian)");
                have_format = true;
            } else if (keyword == "element") {
                if (tokens.size() < 3) c_.fail("incomplete element line at " + c_.where(pos));
                PlyElement element;
                element.name = std::string(tokens[1]);
                if (!parse_u64(tokens[2], element.count))
                    c_.fail("bad count " + quote(tokens[2]) + " for element " + quote(tokens[1]) + " at " + c_.where(pos));
                elements_.push_back(std::move(element));
            } else if (keyword == "property") {
                if (elements_.empty()) c_.fail("property before any element at " + c_.where(pos));
                PlyProperty property;
                if (tokens.size() >= 2 && tokens[1] == "list") {
                    if (tokens.size() < 5) c_.fail("incomplete list property at " + c_.where(pos));
                    property.is_list = true;
                    if (!ply_type_from_name(tokens[2], property.count_type) || !scalar_is_integer(property.count_type))
                        c_.fail("bad list count type " + quote(tokens[2]) + " at " + c_.where(pos));
                    if (!ply_type_from_name(tokens[3], property.type))
                        c_.fail("unknown property type " + quote(tokens[3]) + " at " + c_.where(pos));
                    property.name = std::string(tokens[4]);
                } else {
                    if (tokens.size() < 3) c_.fail("incomplete property line at " + c_.where(pos));
                    if (!ply_type_from_name(tokens[1], property.type))
                        c_.fail("unknown property type " + quote(tokens[1]) + " at " + c_.where(pos));
                    property.name = std::string(tokens[2]);
                }
                elements_.back().properties.push_back(std::move(property));
            } else {
                c_.fail("unknown PLY header line " + quote(keyword) + " at " + c_.where(pos));
            }
        }
        if (!have_format) c_.fail("the PLY header has no format line");
    }

    double value(ScalarType type, const std::string& what) {
        if (format_ == Format::ascii) {
            std::string_view token = c_.token();
            if (token.empty()) c_.fail("truncated at " + c_.where() + ": " + what + " is missing");
            float f = 0.0f;
            if (scalar_is_integer(type)) {
                std::int64_t i = 0;
                if (parse_i64(token, i)) return static_cast<double>(i);
            } else if (parse_float(token, f)) {
                return f;
            }
            c_.fail("bad value " + quote(token) + " for " + what + " at " + c_.where(c_.pos() - token.size()));
        }
        const unsigned char* p = c_.take(scalar_size(type), what);
        return decode_scalar(p, type, format_ == Format::binary_be);
    }

    // The smallest number of bytes one element can take, to bound counts before allocating or looping.
    std::uint64_t min_element_bytes(const PlyElement& element) const {
        std::uint64_t bytes = 0;
        for (const auto& p : element.properties)
            bytes += format_ == Format::ascii ? 2 : scalar_size(p.is_list ? p.count_type : p.type);
        return bytes;
    }

    std::uint64_t list_length(const PlyProperty& p, const std::string& what) {
        double n = value(p.count_type, what + " list length");
        if (!(n >= 0)) c_.fail("negative list length " + std::to_string(static_cast<long long>(n)) + " in " + what + " at " + c_.where());
        std::uint64_t length = static_cast<std::uint64_t>(n);
        std::uint64_t min_bytes = format_ == Format::ascii ? 2 : scalar_size(p.type);
        if (length > (c_.remaining() + 1) / min_bytes)
            c_.fail("list length " + std::to_string(length) + " in " + what + " at " + c_.where() +
                    " cannot fit in the " + std::to_string(c_.remaining()) + " bytes left");
        return length;
    }

    void check_count(const PlyElement& element) {
        std::uint64_t min_bytes = min_element_bytes(element), total = 0;
        if (!checked_mul(element.count, min_bytes, total) || total > c_.remaining() + 1)
            c_.fail("element " + quote(element.name) + " count " + std::to_string(element.count) + " needs at least " +
                    (total ? std::to_string(total) : std::string("an impossible number of")) + " bytes but only " +
                    std::to_string(c_.remaining()) + " remain after " + c_.where());
    }

    void read_element(const PlyElement& element) {
        if (element.name == "vertex" && particles_ && element.properties.empty())
            c_.fail("the vertex element has no x, y and z properties");
        if (element.properties.empty()) return;  // no data at all, whatever the count
        check_count(element);
        if (element.name == "vertex")
            read_vertices(element);
        else if (element.name == "face" && !particles_)
            read_faces(element);
        else
            skip_records(element);
    }

    void skip_records(const PlyElement& element) {
        std::vector<std::string> whats;
        for (const auto& p : element.properties) whats.push_back("property " + quote(p.name) + " of element " + quote(element.name));
        for (std::uint64_t r = 0; r < element.count; ++r)
            for (std::size_t i = 0; i < element.properties.size(); ++i) {
                const auto& p = element.properties[i];
                std::uint64_t n = p.is_list ? list_length(p, whats[i]) : 1;
                for (std::uint64_t j = 0; j < n; ++j) value(p.type, whats[i]);
            }
    }

    void read_vertices(const PlyElement& element) {
        if (have_vertex_element_) c_.fail("second vertex element");
        have_vertex_element_ = true;
        const auto& props = element.properties;
        auto find = [&](const char* name) -> int {
            for (std::size_t i = 0; i < props.size(); ++i)
                if (props[i].name == name && !props[i].is_list) return static_cast<int>(i);
            return -1;
        };
        int ix = find("x"), iy = find("y"), iz = find("z");
        if (ix < 0 || iy < 0 || iz < 0) c_.fail("the vertex element has no x, y and z properties");
        int inx = find("nx"), iny = find("ny"), inz = find("nz");
        bool normals = inx >= 0 && iny >= 0 && inz >= 0 && !particles_;

        const std::size_t n = static_cast<std::size_t>(element.count);
        mesh_.vertices.resize(3 * n);
        if (normals) mesh_.normals.resize(3 * n);
        std::vector<Column> columns(props.size());
        columns[ix] = {&mesh_.vertices, 3, 0};
        columns[iy] = {&mesh_.vertices, 3, 1};
        columns[iz] = {&mesh_.vertices, 3, 2};
        if (normals) {
            columns[inx] = {&mesh_.normals, 3, 0};
            columns[iny] = {&mesh_.normals, 3, 1};
            columns[inz] = {&mesh_.normals, 3, 2};
        }
        plan_attributes(props, columns, n);

        std::vector<std::string> whats;  // built once: a string per value would dominate the reading time
        for (const auto& p : props) whats.push_back("vertex property " + quote(p.name));
        for (std::size_t v = 0; v < n; ++v) {
            for (std::size_t i = 0; i < props.size(); ++i) {
                const auto& p = props[i];
                if (p.is_list) {
                    std::uint64_t len = list_length(p, whats[i]);
                    for (std::uint64_t j = 0; j < len; ++j) value(p.type, whats[i]);
                    continue;
                }
                float x = static_cast<float>(value(p.type, whats[i]));
                const Column& col = columns[i];
                if (col.target) (*col.target)[v * col.components + col.k] = x;
            }
        }
    }

    // Groups the remaining scalar vertex properties into attributes (reversing write_ply's naming) and points
    // their columns at the attribute arrays.
    void plan_attributes(const std::vector<PlyProperty>& props, std::vector<Column>& columns, std::size_t n) {
        std::vector<std::size_t> free;  // property indices not yet used, in file order
        for (std::size_t i = 0; i < props.size(); ++i)
            if (!columns[i].target && !props[i].is_list) free.push_back(i);
        mesh_.attributes.reserve(free.size());  // the vector must not move once columns point into it
        auto ends_with = [](const std::string& s, const std::string& suffix) {
            return s.size() > suffix.size() && s.compare(s.size() - suffix.size(), suffix.size(), suffix) == 0;
        };
        for (std::size_t f = 0; f < free.size();) {
            const std::string& name = props[free[f]].name;
            std::string base;
            int k = 1;
            // Particle files often spell normals and velocities nx ny nz and vx vy vz.
            if (particles_ && f + 2 < free.size() && name.size() == 2 && (name[0] == 'n' || name[0] == 'v') && name[1] == 'x' &&
                props[free[f + 1]].name == std::string(1, name[0]) + "y" && props[free[f + 2]].name == std::string(1, name[0]) + "z") {
                base = name[0] == 'n' ? "normal" : "velocity";
                k = 3;
            }
            if (k == 1 && ends_with(name, "_x") && f + 2 < free.size()) {
                base = name.substr(0, name.size() - 2);
                if (props[free[f + 1]].name == base + "_y" && props[free[f + 2]].name == base + "_z") k = 3;
            }
            if (k == 1 && ends_with(name, "_0")) {
                base = name.substr(0, name.size() - 2);
                int j = 1;
                while (f + j < free.size() && props[free[f + j]].name == base + "_" + std::to_string(j)) ++j;
                if (j >= 2) k = j;
            }
            Attribute a;
            a.name = k == 1 ? name : base;
            a.components = k;
            a.values.resize(n * static_cast<std::size_t>(k));
            a.integral = true;
            for (int j = 0; j < k; ++j) a.integral = a.integral && scalar_is_integer(props[free[f + j]].type);
            mesh_.attributes.push_back(std::move(a));
            for (int j = 0; j < k; ++j) columns[free[f + j]] = {&mesh_.attributes.back().values, k, j};
            f += static_cast<std::size_t>(k);
        }
    }

    void read_faces(const PlyElement& element) {
        int index_property = -1;
        for (std::size_t i = 0; i < element.properties.size(); ++i) {
            const auto& p = element.properties[i];
            if (p.is_list && (p.name == "vertex_indices" || p.name == "vertex_index")) index_property = static_cast<int>(i);
        }
        if (index_property < 0) c_.fail("the face element has no vertex_indices list");
        if (!scalar_is_integer(element.properties[index_property].type))
            c_.fail("face vertex_indices are not of an integer type");
        std::vector<std::int64_t> polygon;
        std::vector<std::string> whats;
        for (const auto& p : element.properties) whats.push_back("face property " + quote(p.name));
        for (std::uint64_t f = 0; f < element.count; ++f) {
            for (std::size_t i = 0; i < element.properties.size(); ++i) {
                const auto& p = element.properties[i];
                const std::string& what = whats[i];
                std::uint64_t len = p.is_list ? list_length(p, what) : 1;
                if (static_cast<int>(i) != index_property) {
                    for (std::uint64_t j = 0; j < len; ++j) value(p.type, what);
                    continue;
                }
                if (len < 3) c_.fail("face " + std::to_string(f) + " has only " + std::to_string(len) + " vertices");
                polygon.clear();
                for (std::uint64_t j = 0; j < len; ++j) {
                    double index = value(p.type, what);
                    if (index < 0 || index > 2147483647.0)
                        c_.fail("face " + std::to_string(f) + " has vertex index " + std::to_string(static_cast<long long>(index)) +
                                " outside the int32 range");
                    polygon.push_back(static_cast<std::int64_t>(index));
                }
                for (std::size_t j = 1; j + 1 < polygon.size(); ++j) {  // fan triangulation
                    mesh_.triangles.push_back(static_cast<std::int32_t>(polygon[0]));
                    mesh_.triangles.push_back(static_cast<std::int32_t>(polygon[j]));
                    mesh_.triangles.push_back(static_cast<std::int32_t>(polygon[j + 1]));
                }
            }
        }
    }
};


// ---- writing -------------------------------------------------------------------------------------------------

std::vector<std::string> ply_attribute_names(const TriMesh& mesh) {
    std::vector<std::string> names;
    for (std::size_t i = 0; i < mesh.attributes.size(); ++i) {
        std::string name = safe_attribute_name(mesh.attributes[i].name, i);
        if (name == "x" || name == "y" || name == "z" || name == "nx" || name == "ny" || name == "nz") name = "attr_" + name;
        names.push_back(name);
    }
    return names;
}


}  // namespace

ParticleData read_ply_particles(const Source& source) {
    TriMesh mesh = PlyReader(source, true).read();
    ParticleData out;
    out.positions = std::move(mesh.vertices);
    out.attributes = std::move(mesh.attributes);
    return out;
}

TriMesh read_ply_mesh(const Source& source) { return PlyReader(source).read(); }

void write_ply_mesh(const TriMesh& mesh, const std::string& path, int threads) {
    const std::size_t nv = mesh.num_vertices(), nt = mesh.num_triangles();
    const bool normals = !mesh.normals.empty();
    std::string header = "ply\nformat binary_little_endian 1.0\ncomment written by meniscus\nelement vertex " +
                         std::to_string(nv) + "\nproperty float x\nproperty float y\nproperty float z\n";
    if (normals) header += "property float nx\nproperty float ny\nproperty float nz\n";
    auto names = ply_attribute_names(mesh);
    for (std::size_t i = 0; i < mesh.attributes.size(); ++i) {
        const int k = mesh.attributes[i].components;
        // Whole-number attributes (ids, labels) stay integers, so that they read back as such.
        const std::string property = mesh.attributes[i].integral ? "property int " : "property float ";
        if (k == 1)
            header += property + names[i] + "\n";
        else if (k == 3)
            for (const char* suffix : {"_x", "_y", "_z"}) header += property + names[i] + suffix + "\n";
        else
            for (int j = 0; j < k; ++j) header += property + names[i] + "_" + std::to_string(j) + "\n";
    }
    header += "element face " + std::to_string(nt + mesh.num_quads()) + "\nproperty list uchar int vertex_indices\nend_header\n";

    FileWriter out(path);
    out.put(header);
    out.put_in_parallel(static_cast<int64_t>(nv), threads, [&](int64_t begin, int64_t end, Encoder& block) {
        for (int64_t v = begin; v < end; ++v) {
            for (int k = 0; k < 3; ++k) block.put_le_float(mesh.vertices[3 * v + k]);
            if (normals)
                for (int k = 0; k < 3; ++k) block.put_le_float(mesh.normals[3 * v + k]);
            for (const auto& a : mesh.attributes)
                for (int k = 0; k < a.components; ++k) {
                    const float value = a.values[v * a.components + k];
                    if (a.integral)
                        block.put_le32(static_cast<std::uint32_t>(
                            std::isfinite(value) ? static_cast<std::int32_t>(std::clamp(value, -2147483648.0f, 2147483520.0f)) : 0));
                    else
                        block.put_le_float(value);
                }
        }
    });
    out.put_in_parallel(static_cast<int64_t>(nt), threads, [&](int64_t begin, int64_t end, Encoder& block) {
        for (int64_t t = begin; t < end; ++t) {
            block.put_u8(3);
            for (int k = 0; k < 3; ++k) block.put_le32(static_cast<std::uint32_t>(mesh.triangles[3 * t + k]));
        }
    });
    for (std::size_t q = 0; q < mesh.num_quads(); ++q) {
        out.put_u8(4);
        for (int k = 0; k < 4; ++k) out.put_le32(static_cast<std::uint32_t>(mesh.quads[4 * q + k]));
    }
    out.close();
}

// Particles: the vertex element of a mesh without faces, with every attribute (write_particles checked the sizes).
void write_ply_particles(const ParticleData& particles, const std::string& path) {
    TriMesh points;
    points.vertices = particles.positions;
    points.attributes = particles.attributes;
    write_ply_mesh(points, path, 1);
}

}  // namespace io_detail
}  // namespace meniscus
