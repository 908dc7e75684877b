// File reading, gzip decompression and the choice of particle reader by content.
#include "io.h"

#include <zlib.h>

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <filesystem>
#include <memory>

#include "io_util.h"

namespace meniscus {
namespace io_detail {

Bytes read_file(const std::string& path) {
    if (path.empty()) fail(path, "no file name given");
    std::error_code ec;
    auto status = std::filesystem::status(path, ec);
    if (std::filesystem::is_directory(status)) fail(path, "is a directory, not a file");
    if (!ec && std::filesystem::exists(status) && !std::filesystem::is_regular_file(status))
        fail(path, "is not a regular file");  // a fifo or device could block or never end

    std::unique_ptr<std::FILE, int (*)(std::FILE*)> file(std::fopen(path.c_str(), "rb"), &std::fclose);
    if (!file) fail(path, std::string("cannot open file: ") + std::strerror(errno));

    Bytes bytes;
    if (std::filesystem::is_regular_file(status)) {
        auto size = std::filesystem::file_size(path, ec);
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

Bytes gunzip(const std::string& path, const Bytes& compressed) {
    const std::uint64_t limit = kGunzipRatioCap * compressed.size() + kGunzipSlackBytes;
    z_stream zs{};
    // 15 + 16: zlib window of 32 KiB, gzip wrapper only (we got here by the gzip magic).
    if (inflateInit2(&zs, 15 + 16) != Z_OK) fail(path, "cannot initialise zlib");
    struct Guard {
        z_stream* zs;
        ~Guard() { inflateEnd(zs); }
    } guard{&zs};

    // First guess of the output size: the gzip trailer's length field when it is plausible (it is mod 2^32, of the
    // last member only, and garbage in a truncated file), else 4x the input. Growth by doubling handles the rest.
    std::uint64_t guess = std::uint64_t(compressed.size()) * 4;
    if (compressed.size() >= 18) {
        std::uint64_t isize = load_le32(compressed.data() + compressed.size() - 4);
        if (isize >= compressed.size() / 2 && isize <= std::uint64_t(compressed.size()) * 16)
            guess = isize + 1;  // +1: room to see the end of the stream without growing
    }
    Bytes out(static_cast<std::size_t>(std::min<std::uint64_t>(limit, std::max<std::uint64_t>(guess, 1 << 16))));
    std::size_t in_pos = 0, out_pos = 0;
    while (true) {
        if (out_pos == out.size()) {
            if (out.size() >= limit)
                fail(path, "gzip data decompresses to more than " + std::to_string(limit) + " bytes (" +
                               std::to_string(kGunzipRatioCap) + " times the compressed size plus " +
                               std::to_string(kGunzipSlackBytes >> 20) + " MiB); refusing a corrupt file or decompression bomb");
            out.resize(static_cast<std::size_t>(std::min<std::uint64_t>(limit, std::uint64_t(out.size()) * 2)));
        }
        // zlib counts in 32-bit units; feed large buffers in slices.
        std::size_t in_slice = std::min<std::size_t>(compressed.size() - in_pos, 1u << 30);
        std::size_t out_slice = std::min<std::size_t>(out.size() - out_pos, 1u << 30);
        zs.next_in = const_cast<Bytef*>(compressed.data() + in_pos);
        zs.avail_in = static_cast<uInt>(in_slice);
        zs.next_out = out.data() + out_pos;
        zs.avail_out = static_cast<uInt>(out_slice);
        int ret = inflate(&zs, Z_NO_FLUSH);
        in_pos += in_slice - zs.avail_in;
        out_pos += out_slice - zs.avail_out;
        if (ret == Z_STREAM_END) {
            // Another gzip member may follow (cat a.gz b.gz); anything else after the end is ignored.
            if (compressed.size() - in_pos >= 2 && compressed[in_pos] == 0x1f && compressed[in_pos + 1] == 0x8b) {
                inflateReset(&zs);
                continue;
            }
            break;
        }
        if (ret == Z_OK) continue;
        if (ret == Z_BUF_ERROR && in_pos == compressed.size())
            fail(path, "truncated gzip stream: the compressed data ends at byte " + std::to_string(compressed.size()) +
                           " before the end of the stream (" + std::to_string(out_pos) + " bytes decompressed so far)");
        if (ret == Z_BUF_ERROR) continue;  // output space was exhausted; grow it above
        if (ret == Z_MEM_ERROR) fail(path, "out of memory while decompressing gzip data");
        fail(path, std::string("corrupt gzip stream near compressed byte ") + std::to_string(in_pos) + ": " +
                       (zs.msg ? zs.msg : "invalid data"));
    }
    out.resize(out_pos);
    out.shrink_to_fit();
    if (out.empty()) fail(path, "empty file (the gzip stream decompresses to nothing)");
    return out;
}

std::string lower_extension(const std::string& path) {
    std::string ext = std::filesystem::path(path).extension().string();
    return to_lower(ext);
}

namespace {

bool starts_with(const Bytes& b, std::string_view prefix) {
    return b.size() >= prefix.size() && std::memcmp(b.data(), prefix.data(), prefix.size()) == 0;
}

enum class ParticleFormat { unknown, vtk, bgeo };

ParticleFormat detect_particle_format(const Bytes& b) {
    if (starts_with(b, "# vtk DataFile")) return ParticleFormat::vtk;
    // "Bgeo" is the classic binary geometry; 0x7f "NSJ" (new binary JSON) and "PGEOMETRY" (ASCII .geo) are other
    // Houdini variants that the BGEO reader recognises in order to name them in its error.
    if (starts_with(b, "Bgeo") || starts_with(b, "\x7fNSJ") || starts_with(b, "PGEOMETRY")) return ParticleFormat::bgeo;
    return ParticleFormat::unknown;
}

}  // namespace
}  // namespace io_detail

ParticleData read_particles(const std::string& path) {
    using namespace io_detail;
    Bytes bytes = read_file(path);
    bool decompressed = false;
    if (has_gzip_magic(bytes)) {
        bytes = gunzip(path, bytes);
        decompressed = true;
    }
    ParticleFormat format = detect_particle_format(bytes);
    if (format == ParticleFormat::unknown) {
        // No magic we know: fall back to the extension (".bgeo.gz" ends in ".gz", so look inside the name too).
        std::string ext = lower_extension(path);
        std::string lower_path = to_lower(path);
        if (ext == ".vtk")
            format = ParticleFormat::vtk;
        else if (ext == ".bgeo" || ext == ".bhclassic" || lower_path.find(".bgeo") != std::string::npos)
            format = ParticleFormat::bgeo;
        else
            fail(path, "unknown particle file format: the content is neither legacy VTK ('# vtk DataFile') nor "
                       "BGEO ('BgeoV'), plain or gzip-compressed");
    }
    Source source{path, bytes.data(), bytes.size(), decompressed};
    return format == ParticleFormat::vtk ? read_vtk_particles(source) : read_bgeo_particles(source);
}

}  // namespace meniscus
