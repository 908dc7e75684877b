// Writing meshes: a buffered output file that never leaves a partial file behind, and helpers shared by the
// PLY, OBJ and VTK mesh writers (formats/ply.cpp, obj.cpp, vtk.cpp).
#pragma once
#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <string>
#include <string_view>
#include <vector>

#include "base/parallel.h"
#include "io/io_util.h"
#include "mesh/mesh.h"
#include "sph/particles.h"

namespace meniscus {
namespace io_detail {

// Binary and text encodings appended to a byte buffer. A FileWriter spills its buffer to the file when it is full;
// a plain Encoder keeps everything (one block of records encoded on its own thread, see put_in_parallel).
class Encoder {
public:
    Encoder() = default;
    Encoder(const Encoder&) = delete;
    Encoder& operator=(const Encoder&) = delete;
    virtual ~Encoder() = default;

    void put(std::string_view text) { put(text.data(), text.size()); }
    // The hot path of every writer (a few bytes at a time): a copy into room already there.
    void put(const void* data, std::size_t n) {
        if (n > buffer_.size() - used_) make_room(n);
        std::memcpy(buffer_.data() + used_, data, n);
        used_ += n;
    }
    void put_u8(std::uint8_t v) { put(&v, 1); }
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

    const char* data() const { return buffer_.data(); }
    std::size_t size() const { return used_; }
    void clear() { used_ = 0; }  // keeps the room

protected:
    std::vector<char> buffer_;  // bytes [0, used_) are encoded; the rest is room
    std::size_t used_ = 0;
    // Room for n more bytes: a plain encoder grows; a FileWriter writes out what it holds.
    virtual void make_room(std::size_t n);
};

// Buffered output that reports every failure (open, write, disk full at close) as a FormatError naming the path,
// and removes the partial file so that a truncated mesh is never mistaken for a complete one.
class FileWriter : public Encoder {
public:
    explicit FileWriter(const std::string& path);
    ~FileWriter() override;

    // Records [0, n) encoded in parallel, encode(begin, end, encoder) per block of records, and written in record
    // order: the file's bytes do not depend on the thread count. One group of blocks is held at a time.
    template <class Encode>
    void put_in_parallel(int64_t n, int threads, Encode&& encode);

    // Flushes and closes the file; a failure (a full disk) removes it and is a FormatError.
    void close();

private:
    static constexpr std::size_t kBufferSize = 1 << 20;
    static constexpr int64_t kRecordsPerBlock = 1 << 14;
    static constexpr int64_t kBlocksPerGroup = 64;
    std::string path_;
    std::FILE* file_ = nullptr;

    void remove_partial() const;
    void flush();
    void write_through(const char* bytes, std::size_t n);  // unbuffered: the buffer is empty
    void make_room(std::size_t n) override;
};

template <class Encode>
void FileWriter::put_in_parallel(int64_t n, int threads, Encode&& encode) {
    if (resolve_threads(threads) <= 1 || n <= kRecordsPerBlock) {
        encode(int64_t{0}, n, static_cast<Encoder&>(*this));
        return;
    }
    const int64_t blocks = (n + kRecordsPerBlock - 1) / kRecordsPerBlock;
    std::vector<Encoder> encoded(static_cast<std::size_t>(std::min(blocks, kBlocksPerGroup)));
    for (int64_t first = 0; first < blocks; first += kBlocksPerGroup) {
        const int64_t count = std::min(kBlocksPerGroup, blocks - first);
        parallel_for(count, threads, [&](int64_t i) {
            const int64_t begin = (first + i) * kRecordsPerBlock;
            encode(begin, std::min(n, begin + kRecordsPerBlock), encoded[static_cast<std::size_t>(i)]);
        });
        flush();
        for (int64_t i = 0; i < count; ++i) {
            Encoder& block = encoded[static_cast<std::size_t>(i)];
            write_through(block.data(), block.size());
            block.clear();  // its room serves the next group
        }
    }
}

// An InputError naming the path when the mesh's arrays disagree (sizes, attribute counts, triangle indices).
void validate_mesh(const TriMesh& mesh, const std::string& path, int threads);

// A name safe for a whitespace-separated header (PLY property, VTK array): white space and control characters become
// '_', an empty name becomes attribute_<index>.
std::string safe_attribute_name(const std::string& name, std::size_t index);

// The writers, one per format; the mesh has been validated. Records are encoded on `threads` threads (0: all).
void write_ply_mesh(const TriMesh& mesh, const std::string& path, int threads);
void write_obj_mesh(const TriMesh& mesh, const std::string& path, int threads);
void write_vtk_mesh(const TriMesh& mesh, const std::string& path, int threads);
// Particle writers (convert): VTK as an unstructured grid of vertex cells; PLY and raw XYZ by their own rules.
void write_vtk_particles(const ParticleData& particles, const std::string& path);
void write_xyz_particles(const ParticleData& particles, const std::string& path);
void write_ply_particles(const ParticleData& particles, const std::string& path);

}  // namespace io_detail
}  // namespace meniscus
