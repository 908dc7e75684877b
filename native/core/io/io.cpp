// File reading, gzip decompression and the choice of particle reader by content.
#include "io/io.h"

#include <zlib.h>

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <filesystem>
#include <memory>

#include "io/io_util.h"
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

void inflate_exact(const std::string& path, const unsigned char* in, std::size_t in_size, unsigned char* out,
                   std::size_t expected, int window_bits, const std::string& what) {
    z_stream zs{};
    if (inflateInit2(&zs, window_bits) != Z_OK) fail(path, "cannot initialise zlib");
    struct Guard {
        z_stream* zs;
        ~Guard() { inflateEnd(zs); }
    } guard{&zs};
    // One spare output byte: a stream that has more to give than `expected` is caught instead of silently cut.
    unsigned char spare = 0;
    std::size_t in_pos = 0, out_pos = 0;
    bool in_spare = expected == 0;  // zlib refuses a null output pointer even for zero bytes
    while (true) {
        std::size_t in_slice = std::min<std::size_t>(in_size - in_pos, 1u << 30);
        std::size_t out_slice = in_spare ? 1 : std::min<std::size_t>(expected - out_pos, 1u << 30);
        zs.next_in = const_cast<Bytef*>(in + in_pos);
        zs.avail_in = static_cast<uInt>(in_slice);
        zs.next_out = in_spare ? &spare : out + out_pos;
        zs.avail_out = static_cast<uInt>(out_slice);
        int ret = inflate(&zs, Z_NO_FLUSH);
        in_pos += in_slice - zs.avail_in;
        std::size_t produced = out_slice - zs.avail_out;
        if (in_spare && produced > 0)
            fail(path, what + ": the compressed data decompresses to more than the " + std::to_string(expected) +
                           " bytes its header announces");
        if (!in_spare) out_pos += produced;
        if (ret == Z_STREAM_END) break;
        if (ret == Z_OK || (ret == Z_BUF_ERROR && zs.avail_out == 0)) {
            if (!in_spare && out_pos == expected) in_spare = true;
            continue;
        }
        if (ret == Z_BUF_ERROR)
            fail(path, what + ": truncated compressed data (" + std::to_string(in_size) + " bytes end before the end of the "
                           "stream, " + std::to_string(out_pos) + " of " + std::to_string(expected) + " bytes decompressed)");
        if (ret == Z_MEM_ERROR) fail(path, what + ": out of memory while decompressing");
        fail(path, what + ": corrupt compressed data near byte " + std::to_string(in_pos) + " of the block: " +
                       (zs.msg ? zs.msg : "invalid data"));
    }
    if (out_pos != expected)
        fail(path, what + ": the compressed data decompresses to " + std::to_string(out_pos) + " bytes, " +
                       std::to_string(expected) + " expected");
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

enum class ParticleFormat { unknown, vtk, bgeo, houdini_json, vtu, ply, npy, npz, csv, xyz };

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
                       "('<VTKFile'), BGEO ('BgeoV' or Houdini JSON geometry), PLY ('ply'), NumPy ('\\x93NUMPY' or a zip), or CSV with an x,y,z "
                       "header, plain or gzip-compressed; raw float32 XYZ files need the extension .xyz");
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
        case ParticleFormat::unknown: break;
    }
    fail(path, "unknown particle file format");
}

}  // namespace io_detail

ParticleData read_particles(const std::string& path) { return io_detail::read_particles_from_bytes(path, io_detail::read_file(path)); }

}  // namespace meniscus
