// File reading and the choice of reader: particle formats by content (falling back to the extension), mesh formats
// by content or extension.
#include "io/io.h"

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <filesystem>
#include <initializer_list>
#include <memory>
#include <utility>

#include "io/formats/mantaflow.h"
#include "io/io_util.h"
#include "io/mesh_writer.h"
#include "base/platform.h"

namespace meniscus {
namespace io_detail {

Bytes read_file(const std::string& path) {
    if (path.empty()) fail(path, "no file name given");
    std::error_code ec;
    const std::filesystem::path native = path_from_utf8(path);
    auto status = std::filesystem::status(native, ec);
    if (std::filesystem::is_directory(status)) fail(path, "is a directory, not a file");
    if (!ec && std::filesystem::exists(status) && !std::filesystem::is_regular_file(status))
        fail(path, "is not a regular file");  // a fifo or device could block or never end

    std::unique_ptr<std::FILE, int (*)(std::FILE*)> file(open_file(path, "rb"), &std::fclose);
    if (!file) fail(path, std::string("cannot open file: ") + std::strerror(errno));

    Bytes bytes;
    if (std::filesystem::is_regular_file(status)) {
        auto size = std::filesystem::file_size(native, ec);
        if (!ec) bytes.reserve(static_cast<std::size_t>(size));
    }
    unsigned char chunk[1 << 16];
    while (true) {
        std::size_t n = std::fread(chunk, 1, sizeof chunk, file.get());
        bytes.insert(bytes.end(), chunk, chunk + n);
        if (n < sizeof chunk) break;
    }
    if (std::ferror(file.get())) fail(path, std::string("read error: ") + std::strerror(errno));
    if (bytes.empty()) fail(path, "empty file");
    return bytes;
}

std::string lower_extension(const std::string& path) {
    std::string ext = path_to_utf8(path_from_utf8(path).extension());
    return to_lower(ext);
}

namespace {

bool starts_with(const Bytes& b, std::string_view prefix) {
    return b.size() >= prefix.size() && std::memcmp(b.data(), prefix.data(), prefix.size()) == 0;
}

bool ends_with(std::string_view s, std::string_view suffix) {
    return s.size() >= suffix.size() && s.compare(s.size() - suffix.size(), suffix.size(), suffix) == 0;
}

enum class ParticleFormat { unknown, vtk, bgeo, houdini_json, vtu, ply, npy, npz, csv, xyz, mantaflow_uni, vdb };

// Houdini's ASCII JSON geometry: a JSON array whose first keys (within the first KiB) include "fileversion" or
// "pointcount".
bool looks_like_houdini_json(const Bytes& b) {
    std::size_t i = 0;
    while (i < b.size() && i < 1024 && Cursor::is_space(b[i])) ++i;
    if (i >= b.size() || (b[i] != '[' && b[i] != '{')) return false;
    std::string_view head(reinterpret_cast<const char*>(b.data()), std::min<std::size_t>(b.size(), 1024));
    return head.find("\"fileversion\"") != std::string_view::npos || head.find("\"pointcount\"") != std::string_view::npos;
}

// XML after an optional UTF-8 byte order mark and white space: the VTK XML formats (.vtu, .vtp).
bool looks_like_xml(const Bytes& b) {
    std::size_t i = starts_with(b, "\xef\xbb\xbf") ? 3 : 0;
    while (i < b.size() && i < 4096 && Cursor::is_space(b[i])) ++i;
    return i < b.size() && b[i] == '<';
}

// A text file whose first non-comment line names the columns x, y and z (or Points:0..2): CSV. Only the first 64 KiB are looked at.
bool looks_like_csv_header(const Bytes& b) {
    std::size_t i = 0, n = std::min<std::size_t>(b.size(), 1 << 16);
    while (i < n) {
        std::size_t end = i;
        while (end < n && b[end] != '\n') ++end;
        std::string line = to_lower(std::string_view(reinterpret_cast<const char*>(b.data()) + i, end - i));
        i = end + 1;
        if (line.find_first_not_of(" \t\r") == std::string::npos || line[line.find_first_not_of(" \t\r")] == '#') continue;
        bool x = false, y = false, z = false;
        std::string token;
        for (std::size_t k = 0; k <= line.size(); ++k) {
            char c = k < line.size() ? line[k] : ',';
            if (c == ',' || c == ';' || c == '\t' || c == ' ' || c == '\r' || c == '"') {
                x = x || token == "x" || token == "points:0";  // ParaView writes Points:0, Points:1, Points:2
                y = y || token == "y" || token == "points:1";
                z = z || token == "z" || token == "points:2";
                token.clear();
            } else {
                token += c;
            }
        }
        return x && y && z;
    }
    return false;
}

ParticleFormat detect_particle_format(const Bytes& b) {
    if (starts_with(b, "# vtk DataFile")) return ParticleFormat::vtk;
    // Houdini: "Bgeo" is the classic binary geometry; 0x7f "NSJb" / "bJSN" is binary JSON geometry (Houdini 12+, either
    // byte order), a JSON array its ASCII form. Other 0x7f "NSJ" headers and "PGEOMETRY" (classic ASCII .geo) go to
    // the BGEO reader, which names them in its error.
    if (starts_with(b, "\x7fNSJb") || starts_with(b, "\x7f" "bJSN")) return ParticleFormat::houdini_json;
    if (starts_with(b, "Bgeo") || starts_with(b, "\x7fNSJ") || starts_with(b, "PGEOMETRY")) return ParticleFormat::bgeo;
    if (looks_like_houdini_json(b)) return ParticleFormat::houdini_json;
    // Houdini's Blosc-compressed .sc container.
    if (starts_with(b, "scf1")) return ParticleFormat::unknown;
    if (starts_with(b, "ply\n") || starts_with(b, "ply\r")) return ParticleFormat::ply;
    // Mantaflow (Blender's fluid cache) particle systems; the PB01 and PD01 files go there to be named in its error.
    if (starts_with(b, "PB02") || starts_with(b, "PB01")) return ParticleFormat::mantaflow_uni;
    if (starts_with(b, " BDV")) return ParticleFormat::vdb;  // OpenVDB (point data grids)
    if (starts_with(b, "\x93NUMPY")) return ParticleFormat::npy;
    if (starts_with(b, "PK\x03\x04") || starts_with(b, "PK\x05\x06")) return ParticleFormat::npz;
    if (looks_like_xml(b)) return ParticleFormat::vtu;
    if (looks_like_csv_header(b)) return ParticleFormat::csv;
    return ParticleFormat::unknown;
}

}  // namespace

ParticleData read_particles_from_bytes(const std::string& path, Bytes bytes) {
    bool decompressed = false;
    if (has_gzip_magic(bytes)) {
        bytes = gunzip(path, bytes);
        decompressed = true;
    }
    ParticleFormat format = detect_particle_format(bytes);
    if (format == ParticleFormat::unknown) {
        // No magic we know: fall back to the extension (".bgeo.gz" ends in ".gz", so look inside the name too).
        std::string lower_path = to_lower(path);
        // "frame.xyz.gz": once the gzip layer is undone, the extension inside it counts.
        std::string ext = lower_extension(decompressed && ends_with(lower_path, ".gz") ? path.substr(0, path.size() - 3) : path);
        if (ends_with(lower_path, ".sc") || starts_with(bytes, "scf1"))
            fail(path, "Houdini Blosc-compressed geometry (.sc) is not supported (meniscus has no Blosc decoder); save "
                       "the cache as .bgeo or .bgeo.gz, or convert it with Houdini's gconvert");
        if (starts_with(bytes, "PD01"))
            fail(path, "Mantaflow particle data (such as the velocities in pVel_####.uni) holds no positions: read the "
                       "frame's particle file pp_####.uni, which takes its velocities from here");
        if (starts_with(bytes, "MNT") || starts_with(bytes, "M4T"))
            fail(path, "a Mantaflow grid (such as vel_####.uni), not particles: read the frame's particle file pp_####.uni");
        if (ext == ".vtk")
            format = ParticleFormat::vtk;
        else if (ext == ".bgeo" || ext == ".bhclassic" || lower_path.find(".bgeo") != std::string::npos)
            format = ParticleFormat::bgeo;
        else if (ext == ".geo")
            format = ParticleFormat::houdini_json;
        else if (ext == ".vtu" || ext == ".vtp")
            format = ParticleFormat::vtu;
        else if (ext == ".ply")
            format = ParticleFormat::ply;
        else if (ext == ".npy")
            format = ParticleFormat::npy;
        else if (ext == ".npz")
            format = ParticleFormat::npz;
        else if (ext == ".csv")
            format = ParticleFormat::csv;
        else if (ext == ".xyz")
            format = ParticleFormat::xyz;
        else
            fail(path, "unknown particle file format: the content is none of legacy VTK ('# vtk DataFile'), VTK XML "
                       "('<VTKFile'), BGEO ('BgeoV' or Houdini JSON geometry), PLY ('ply'), NumPy ('\\x93NUMPY' or a zip), "
                       "Mantaflow UNI ('PB02'), OpenVDB (' BDV'), or CSV with an x,y,z header, plain or gzip-compressed; "
                       "raw float32 XYZ files need the extension .xyz");
    }
    Source source{path, bytes.data(), bytes.size(), decompressed};
    switch (format) {
        case ParticleFormat::vtk: return read_vtk_particles(source);
        case ParticleFormat::bgeo: return read_bgeo_particles(source);
        case ParticleFormat::houdini_json: return read_houdini_json_particles(source);
        case ParticleFormat::vtu: return read_vtu_particles(source);
        case ParticleFormat::ply: return read_ply_particles(source);
        case ParticleFormat::npy: return read_npy_particles(source);
        case ParticleFormat::npz: return read_npz_particles(source);
        case ParticleFormat::csv: return read_csv_particles(source);
        case ParticleFormat::xyz: return read_xyz_particles(source);
        case ParticleFormat::mantaflow_uni: return read_mantaflow_uni_particles(source);
        case ParticleFormat::vdb: return read_vdb_particles(source);
        case ParticleFormat::unknown: break;
    }
    fail(path, "unknown particle file format");
}

TriMesh read_mesh_from_bytes(const std::string& path, Bytes bytes) {
    bool decompressed = false;
    if (has_gzip_magic(bytes)) {
        bytes = gunzip(path, bytes);
        decompressed = true;
    }
    Source source{path, bytes.data(), bytes.size(), decompressed};
    const std::string ext = lower_extension(path);
    const bool ply_magic = bytes.size() >= 4 && std::memcmp(bytes.data(), "ply", 3) == 0 && (bytes[3] == '\n' || bytes[3] == '\r');
    if (ply_magic) return read_ply_mesh(source);
    if (starts_with(bytes, "# vtk DataFile")) return read_vtk_mesh(source);
    if (ext == ".ply") return read_ply_mesh(source);
    if (ext == ".obj") return read_obj_mesh(source);
    // Mantaflow's own surface: fluid_mesh_####.bobj.gz (no magic; the name says it).
    if (ext == ".bobj" || (decompressed && ends_with(to_lower(path), ".bobj.gz"))) return read_mantaflow_bobj_mesh(source);
    if (ext == ".vtk") return read_vtk_mesh(source);
    fail(path, "unknown mesh format: not PLY (no 'ply' header) or legacy VTK (no '# vtk DataFile' header) and the "
               "extension " + (ext.empty() ? std::string("is missing") : "'" + ext + "' is none of them") +
               " (supported: .ply, .obj, .vtk) or Mantaflow's .bobj.gz");
}

}  // namespace io_detail

ParticleData read_particles(const std::string& path) { return io_detail::read_particles_from_bytes(path, io_detail::read_file(path)); }

TriMesh read_mesh(const std::string& path) { return io_detail::read_mesh_from_bytes(path, io_detail::read_file(path)); }

namespace {

using MeshWriter = void (*)(const TriMesh&, const std::string&, int threads);
using ParticleWriter = void (*)(const ParticleData&, const std::string&);

// The writer for the path's extension; an InputError listing the supported ones when there is none.
template <class Writer>
Writer writer_for(const std::string& path, const char* what, std::initializer_list<std::pair<const char*, Writer>> writers) {
    const std::string ext = io_detail::lower_extension(path);
    std::string supported;
    for (const auto& [extension, writer] : writers) {
        if (ext == extension) return writer;
        supported += std::string(supported.empty() ? "" : ", ") + extension;
    }
    throw InputError(std::string("cannot write ") + what + " to " + path + ": unknown extension " +
                     (ext.empty() ? std::string("(none)") : "'" + ext + "'") + " (supported: " + supported + ")");
}

}  // namespace

void write_mesh(const TriMesh& mesh, const std::string& path, int threads) {
    const MeshWriter write = writer_for<MeshWriter>(
        path, "mesh", {{".ply", io_detail::write_ply_mesh}, {".obj", io_detail::write_obj_mesh}, {".vtk", io_detail::write_vtk_mesh}});
    io_detail::validate_mesh(mesh, path, threads);
    write(mesh, path, threads);
}

void write_particles(const ParticleData& particles, const std::string& path) {
    const ParticleWriter write = writer_for<ParticleWriter>(
        path, "particles",
        {{".vtk", io_detail::write_vtk_particles}, {".ply", io_detail::write_ply_particles}, {".xyz", io_detail::write_xyz_particles}});
    if (particles.positions.size() % 3 != 0)
        throw InputError("cannot write particles to " + path + ": positions has " + std::to_string(particles.positions.size()) +
                         " floats, not a multiple of 3");
    require_one_tuple_per_element(particles.attributes, particles.size(), "cannot write particles to " + path, "particle");
    write(particles, path);
}

}  // namespace meniscus
