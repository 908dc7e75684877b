// Wavefront OBJ meshes: positions, normals and faces (polygons fanned into triangles; texture coordinates and the
// other statements are skipped). Written with normals as "f v//n" corners.
#include "io/io_util.h"
#include "io/mesh_writer.h"

namespace meniscus {
namespace io_detail {
namespace {


bool is_known_obj_statement(std::string_view s) {
    static const char* known[] = {"v",     "vt",    "vn",   "vp",    "f",     "l",     "p",      "o",
                                  "g",     "s",     "mg",   "usemtl", "mtllib", "cstype", "deg",   "bmat",
                                  "step",  "curv",  "curv2", "surf",  "parm",  "trim",  "hole",   "scrv",
                                  "sp",    "end",   "con",  "lod",   "ctech", "stech", "bevel", "c_interp",
                                  "d_interp", "shadow_obj", "trace_obj", "call", "csh", "maplib", "usemap"};
    for (const char* k : known)
        if (s == k) return true;
    return false;
}

// The statements of an OBJ file, line by line; faces are kept as fanned corner triples until the end, where every
// index is checked (a face may in principle precede the vertices it uses).
class ObjParser {
public:
    explicit ObjParser(const Source& source) : c_(source) {}

    TriMesh read() {
        while (!c_.at_end()) read_line();
        return assemble();
    }

private:
    Cursor c_;
    std::vector<float> positions_, normals_;
    std::vector<std::int64_t> corners_;  // pairs (vertex, normal), 0-based; normal -1 when absent
    std::vector<std::int64_t> polygon_;  // the current face's corners, same layout
    std::size_t line_no_ = 0;

    [[noreturn]] void fail_line(const std::string& what) const { c_.fail("line " + std::to_string(line_no_) + ": " + what); }

    void read_line() {
        ++line_no_;
        auto tokens = split_tokens(c_.line());
        for (std::size_t t = 0; t < tokens.size(); ++t)
            if (tokens[t][0] == '#') {  // a comment runs to the end of the line
                tokens.resize(t);
                break;
            }
        if (tokens.empty()) return;
        std::string_view keyword = tokens[0];
        if (keyword == "v")
            read_vec3(tokens, positions_);
        else if (keyword == "vn")
            read_vec3(tokens, normals_);
        else if (keyword == "f")
            read_face(tokens);
        else if (!is_known_obj_statement(keyword))
            fail_line("unknown OBJ statement " + quote(keyword));
    }

    void read_vec3(const std::vector<std::string_view>& tokens, std::vector<float>& out) const {
        if (tokens.size() < 4) fail_line(std::string(tokens[0]) + " needs 3 numbers");
        for (int k = 1; k <= 3; ++k) {
            float x = 0.0f;
            if (!parse_float(tokens[k], x)) fail_line("bad number " + quote(tokens[k]));
            out.push_back(x);
        }
    }

    // Resolves a 1-based or negative (relative) OBJ index; positive ones are range-checked in assemble().
    std::int64_t resolve(std::string_view text, std::size_t defined, const char* what) const {
        std::int64_t i = 0;
        if (!parse_i64(text, i) || i == 0) fail_line(std::string("bad ") + what + " index " + quote(text));
        if (i < 0) {
            if (static_cast<std::uint64_t>(-(i + 1)) >= defined)
                fail_line(std::string("relative ") + what + " index " + std::to_string(i) + " reaches before the first one");
            return static_cast<std::int64_t>(defined) + i;
        }
        return i - 1;
    }

    // "f v v v ...", each corner v, v/t, v//n or v/t/n; fanned into triangles.
    void read_face(const std::vector<std::string_view>& tokens) {
        if (tokens.size() < 4) fail_line("a face needs at least 3 vertices");
        polygon_.clear();
        for (std::size_t t = 1; t < tokens.size(); ++t) {
            std::string_view corner = tokens[t];
            std::size_t slash = corner.find('/');
            std::int64_t v = resolve(corner.substr(0, slash), positions_.size() / 3, "vertex");
            std::int64_t n = -1;
            if (slash != std::string_view::npos) {
                std::size_t slash2 = corner.find('/', slash + 1);
                if (slash2 != std::string_view::npos && slash2 + 1 < corner.size())
                    n = resolve(corner.substr(slash2 + 1), normals_.size() / 3, "normal");
            }
            polygon_.push_back(v);
            polygon_.push_back(n);
        }
        const std::size_t count = polygon_.size() / 2;
        for (std::size_t j = 1; j + 1 < count; ++j)
            for (std::size_t m : {std::size_t(0), j, j + 1}) {
                corners_.push_back(polygon_[2 * m]);
                corners_.push_back(polygon_[2 * m + 1]);
            }
    }

    TriMesh assemble() {
        TriMesh mesh;
        const std::size_t nv = positions_.size() / 3, nn = normals_.size() / 3;
        bool all_normals = !corners_.empty() && nn > 0;
        for (std::size_t i = 0; i < corners_.size(); i += 2) {
            if (corners_[i] < 0 || static_cast<std::uint64_t>(corners_[i]) >= nv)
                c_.fail("a face refers to vertex " + std::to_string(corners_[i] + 1) + " but there are only " + std::to_string(nv) + " vertices");
            if (corners_[i + 1] >= 0 && static_cast<std::uint64_t>(corners_[i + 1]) >= nn)
                c_.fail("a face refers to normal " + std::to_string(corners_[i + 1] + 1) + " but there are only " + std::to_string(nn) + " normals");
            if (corners_[i + 1] < 0) all_normals = false;
            mesh.triangles.push_back(static_cast<std::int32_t>(corners_[i]));
        }
        mesh.vertices = std::move(positions_);
        if (all_normals) mesh.normals = vertex_normals(nv, nn);
        return mesh;
    }

    // Per-vertex normals: the normal of each vertex's first corner (exact for files that pair v and vn one to one).
    std::vector<float> vertex_normals(std::size_t nv, std::size_t nn) const {
        std::vector<float> out(3 * nv, 0.0f);
        std::vector<char> assigned(nv, 0);
        for (std::size_t i = 0; i < corners_.size(); i += 2) {
            std::size_t v = static_cast<std::size_t>(corners_[i]), n = static_cast<std::size_t>(corners_[i + 1]);
            if (assigned[v]) continue;
            assigned[v] = 1;
            for (int k = 0; k < 3; ++k) out[3 * v + k] = normals_[3 * n + k];
        }
        if (nn == nv)  // also covers vertices no face uses, when v and vn correspond one to one
            for (std::size_t v = 0; v < nv; ++v)
                if (!assigned[v])
                    for (int k = 0; k < 3; ++k) out[3 * v + k] = normals_[3 * v + k];
        return out;
    }
};

}  // namespace

TriMesh read_obj_mesh(const Source& source) { return ObjParser(source).read(); }

void write_obj_mesh(const TriMesh& mesh, const std::string& path, int threads) {
    const std::size_t nv = mesh.num_vertices(), nt = mesh.num_triangles();
    const bool normals = !mesh.normals.empty();
    FileWriter out(path);
    out.put("# written by meniscus: " + std::to_string(nv) + " vertices, " + std::to_string(nt) + " triangles, " +
            std::to_string(mesh.num_quads()) + " quads\n");
    auto put_vectors = [&](const char* tag, const std::vector<float>& data) {
        out.put_in_parallel(static_cast<int64_t>(nv), threads, [&](int64_t begin, int64_t end, Encoder& block) {
            for (int64_t i = begin; i < end; ++i) {
                block.put(tag);
                for (int k = 0; k < 3; ++k) {
                    block.put(" ");
                    block.put_float_text(data[3 * i + k]);
                }
                block.put("\n");
            }
        });
    };
    put_vectors("v", mesh.vertices);
    if (normals) put_vectors("vn", mesh.normals);
    auto put_face = [&](Encoder& block, const int32_t* corners, int count) {
        block.put("f");
        for (int k = 0; k < count; ++k) {
            long long index = static_cast<long long>(corners[k]) + 1;  // OBJ counts from 1
            block.put(" ");
            block.put_int_text(index);
            if (normals) {
                block.put("//");
                block.put_int_text(index);
            }
        }
        block.put("\n");
    };
    out.put_in_parallel(static_cast<int64_t>(nt), threads, [&](int64_t begin, int64_t end, Encoder& block) {
        for (int64_t t = begin; t < end; ++t) put_face(block, &mesh.triangles[3 * t], 3);
    });
    for (std::size_t q = 0; q < mesh.num_quads(); ++q) put_face(out, &mesh.quads[4 * q], 4);
    out.close();
}


}  // namespace io_detail
}  // namespace meniscus
