#include "io/mesh_writer.h"

#include <cerrno>
#include <charconv>
#include <filesystem>
#include <tuple>

#include "base/decimal.h"
#include "base/platform.h"

namespace meniscus {
namespace io_detail {

FileWriter::FileWriter(const std::string& path) : path_(path) {
    file_ = open_file(path, "wb");
    if (!file_) fail(path, std::string("cannot open for writing: ") + std::strerror(errno));
    buffer_.resize(kBufferSize);
}

FileWriter::~FileWriter() {
    if (file_) {  // an exception is unwinding: drop the partial file
        std::fclose(file_);
        remove_partial();
    }
}

// Shortest text that reads back as the same float.
void Encoder::put_float_text(float f) {
    char text[32];
    put(text, static_cast<std::size_t>(format_decimal(text, f) - text));
}

void Encoder::put_int_text(long long v) {
    char text[24];
    auto r = std::to_chars(text, text + sizeof text, v);
    put(text, static_cast<std::size_t>(r.ptr - text));
}

void FileWriter::close() {
    flush();
    std::FILE* f = file_;
    file_ = nullptr;
    bool ok = std::fflush(f) == 0;
    int err = errno;
    if (std::fclose(f) != 0 && ok) {
        ok = false;
        err = errno;
    }
    if (!ok) {
        remove_partial();
        fail(path_, std::string("write error: ") + std::strerror(err));
    }
}

// Only a regular file we wrote is removed: a symlink or device given as the output path stays.
void FileWriter::remove_partial() const {
    std::error_code ec;
    if (std::filesystem::is_regular_file(std::filesystem::symlink_status(path_from_utf8(path_), ec))) remove_file(path_);
}

void FileWriter::flush() {
    write_through(buffer_.data(), used_);
    used_ = 0;
}

void FileWriter::write_through(const char* bytes, std::size_t n) {
    if (n == 0) return;
    if (std::fwrite(bytes, 1, n, file_) != n) fail(path_, std::string("write error: ") + std::strerror(errno));
}

void FileWriter::make_room(std::size_t n) {
    flush();
    if (n > buffer_.size()) buffer_.resize(n);
}

void Encoder::make_room(std::size_t n) { buffer_.resize(std::max({2 * buffer_.size(), used_ + n, std::size_t{4096}})); }

void validate_mesh(const TriMesh& mesh, const std::string& path, int threads) {
    auto bad = [&](const std::string& what) { throw InputError("cannot write mesh to " + path + ": " + what); };
    if (mesh.vertices.size() % 3 != 0) bad("vertices has " + std::to_string(mesh.vertices.size()) + " floats, not a multiple of 3");
    if (mesh.triangles.size() % 3 != 0)
        bad("triangles has " + std::to_string(mesh.triangles.size()) + " indices, not a multiple of 3");
    const std::size_t nv = mesh.num_vertices();
    if (!mesh.normals.empty() && mesh.normals.size() != mesh.vertices.size())
        bad("normals has " + std::to_string(mesh.normals.size()) + " floats for " + std::to_string(nv) + " vertices");
    for (const auto& a : mesh.attributes)
        if (a.components < 1 || a.values.size() != nv * static_cast<std::size_t>(a.components))
            bad("attribute '" + a.name + "' has " + std::to_string(a.values.size()) + " values with " +
                std::to_string(a.components) + " components for " + std::to_string(nv) + " vertices");
    if (mesh.quads.size() % 4 != 0) bad("quads has " + std::to_string(mesh.quads.size()) + " indices, not a multiple of 4");
    for (const auto& [faces, corners, kind] : {std::tuple(&mesh.triangles, 3, "triangle"), std::tuple(&mesh.quads, 4, "quad")})
        if (const std::size_t i = first_index_out_of_range(*faces, nv, threads); i < faces->size())
            bad(std::string(kind) + " " + std::to_string(i / corners) + " refers to vertex " + std::to_string((*faces)[i]) +
                " but there are " + std::to_string(nv) + " vertices");
}


std::string safe_attribute_name(const std::string& name, std::size_t index) {
    if (name.empty()) return "attribute_" + std::to_string(index);
    std::string out = name;
    for (char& c : out)
        if (static_cast<unsigned char>(c) <= 32 || c == 127) c = '_';
    return out;
}


}  // namespace io_detail
}  // namespace meniscus
