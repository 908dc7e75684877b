// Writing meshes: a buffered output file that never leaves a partial file behind, and helpers shared by the
// PLY, OBJ and VTK mesh writers (formats/ply.cpp, obj.cpp, vtk.cpp).
#pragma once
#include <cstdint>
#include <cstdio>
#include <string>
#include <string_view>
#include <vector>

#include "io/io_util.h"
#include "mesh/mesh.h"
#include "sph/particles.h"

namespace meniscus {
namespace io_detail {

// Buffered output that reports every failure (open, write, disk full at close) as a FormatError naming the path,
// and removes the partial file so that a truncated mesh is never mistaken for a complete one.
class FileWriter {
public:
    explicit FileWriter(const std::string& path);
    ~FileWriter();
    FileWriter(const FileWriter&) = delete;
    FileWriter& operator=(const FileWriter&) = delete;

    void put(std::string_view text) { put(text.data(), text.size()); }
    void put(const void* data, std::size_t n) {
        const char* p = static_cast<const char*>(data);
        buffer_.insert(buffer_.end(), p, p + n);
        if (buffer_.size() >= kBufferSize) flush();
    }
    void put_u8(std::uint8_t v) { buffer_.push_back(static_cast<char>(v)); }
    void put_le32(std::uint32_t v) {
        char b[4] = {char(v), char(v >> 8), char(v >> 16), char(v >> 24)};
        put(b, 4);
    }
    void put_be32(std::uint32_t v) {
        char b[4] = {char(v >> 24), char(v >> 16), char(v >> 8), char(v)};
        put(b, 4);
    }
    void put_le_float(float f) { put_le32(float_to_bits(f)); }
    void put_be_float(float f) { put_be32(float_to_bits(f)); }
    // Shortest text that reads back as the same float.
    void put_float_text(float f);
    void put_int_text(long long v);

    // Flushes and closes the file; a failure (a full disk) removes it and is a FormatError.
    void close();

private:
    static constexpr std::size_t kBufferSize = 1 << 20;
    std::string path_;
    std::FILE* file_ = nullptr;
    std::vector<char> buffer_;

    void remove_partial() const;
    void flush();
};


// An InputError naming the path when the mesh's arrays disagree (sizes, attribute counts, triangle indices).
void validate_mesh(const TriMesh& mesh, const std::string& path);

// A name safe for a whitespace-separated header (PLY property, VTK array): white space and control characters become
// '_', an empty name becomes attribute_<index>.
std::string safe_attribute_name(const std::string& name, std::size_t index);

// The writers, one per format; the mesh has been validated.
void write_ply_mesh(const TriMesh& mesh, const std::string& path);
void write_obj_mesh(const TriMesh& mesh, const std::string& path);
void write_vtk_mesh(const TriMesh& mesh, const std::string& path);
// Particle writers (convert): VTK as an unstructured grid of vertex cells; PLY and raw XYZ by their own rules.
void write_vtk_particles(const ParticleData& particles, const std::string& path);
void write_xyz_particles(const ParticleData& particles, const std::string& path);
void write_ply_particles(const ParticleData& particles, const std::string& path);

}  // namespace io_detail
}  // namespace meniscus
