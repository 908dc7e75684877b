// Internal helpers shared by the file readers and writers (not part of the public API): whole-file reading,
// gzip decompression, a bounds-checked cursor over a byte buffer (binary and text), number parsing and
// endian conversion. Every failure is a FormatError whose message starts with the file path.
#pragma once
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstdlib>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <string>
#include <string_view>
#include <system_error>
#include <vector>

#include "base/decimal.h"
#include "base/errors.h"
#include "mesh/mesh.h"
#include "sph/particles.h"

namespace meniscus {
namespace io_detail {

using Bytes = std::vector<unsigned char>;

[[noreturn]] inline void fail(const std::string& path, const std::string& what) {
    throw FormatError((path.empty() ? std::string("(empty path)") : path) + ": " + what);
}

// Reads a whole regular file. Directories, devices, missing or unreadable paths and empty files are FormatErrors.
Bytes read_file(const std::string& path);

inline bool has_gzip_magic(const Bytes& bytes) { return bytes.size() >= 2 && bytes[0] == 0x1f && bytes[1] == 0x8b; }

// Decompresses a gzip file (several concatenated members are allowed; trailing non-gzip bytes are ignored, like
// gzip(1) does). The output is capped at kGunzipRatioCap * compressed size + kGunzipSlackBytes: real particle data
// compresses by a few times at most, so anything beyond that is a corrupt file or a decompression bomb and is refused
// before it can exhaust memory. Truncated and corrupt streams are FormatErrors.
constexpr std::uint64_t kGunzipRatioCap = 64;
constexpr std::uint64_t kGunzipSlackBytes = std::uint64_t(64) << 20;
Bytes gunzip(const std::string& path, const Bytes& compressed);

// Lower-case extension including the dot (".vtk"), or "" when there is none.
std::string lower_extension(const std::string& path);

// The bytes of one (possibly decompressed) file, as given to the format readers.
struct Source {
    std::string path;
    const unsigned char* data = nullptr;
    std::size_t size = 0;
    bool decompressed = false;  // byte offsets in messages then refer to the decompressed data
};

// The particle readers, one per format (formats/vtk.cpp, bgeo.cpp, vtu.cpp, ply.cpp, numpy.cpp, text.cpp,
// houdini.cpp). Each takes the whole (decompressed) file and throws FormatError on anything it cannot read.
ParticleData read_vtk_particles(const Source& source);
ParticleData read_bgeo_particles(const Source& source);
ParticleData read_vtu_particles(const Source& source);    // VTK XML: .vtu (UnstructuredGrid), .vtp (PolyData)
ParticleData read_ply_particles(const Source& source);    // the vertex element of a PLY file
ParticleData read_npy_particles(const Source& source);    // NumPy .npy: (N,3) or a structured array
ParticleData read_npz_particles(const Source& source);    // NumPy .npz: a zip of .npy members
ParticleData read_csv_particles(const Source& source);    // delimited text with a header naming x, y, z
ParticleData read_xyz_particles(const Source& source);    // raw little-endian float32 triples, or x y z text lines
ParticleData read_houdini_json_particles(const Source& source);  // Houdini 12+ JSON geometry: ASCII .geo, binary .bgeo
ParticleData read_vdb_points(const Source& source);  // OpenVDB point data grids (formats/vdb_points.cpp)

// The mesh readers (formats/ply.cpp, obj.cpp, vtk.cpp), the same way.
TriMesh read_ply_mesh(const Source& source);
TriMesh read_obj_mesh(const Source& source);
TriMesh read_vtk_mesh(const Source& source);  // legacy VTK POLYDATA with POLYGONS

// Format detection and dispatch on bytes already in memory (gzip is undone first); `path` names the file in
// messages and its extension decides where the content has no magic. read_particles(path) is read_file + this; the
// fuzz harnesses call it directly.
ParticleData read_particles_from_bytes(const std::string& path, Bytes bytes);
TriMesh read_mesh_from_bytes(const std::string& path, Bytes bytes);  // read_mesh without the file

// Inflates a zlib stream (window_bits 15) or raw deflate data (window_bits -15) that must decompress to exactly
// `expected` bytes into `out` (which holds them). Corrupt, short or overlong streams are FormatErrors naming `what`.
void inflate_exact(const std::string& path, const unsigned char* in, std::size_t in_size, unsigned char* out,
                   std::size_t expected, int window_bits, const std::string& what);

// The largest output a compressed block of `compressed` bytes may claim before it is refused as corrupt or a
// decompression bomb (the same cap as for gzip files).
inline std::uint64_t max_inflated_size(std::uint64_t compressed) { return kGunzipRatioCap * compressed + kGunzipSlackBytes; }

// ---- number helpers ------------------------------------------------------------------------------------------

// a * b without overflow; false when the product does not fit.
inline bool checked_mul(std::uint64_t a, std::uint64_t b, std::uint64_t& out) {
    if (a != 0 && b > UINT64_MAX / a) return false;
    out = a * b;
    return true;
}

inline bool parse_u64(std::string_view s, std::uint64_t& out) {
    if (!s.empty() && s[0] == '+') s.remove_prefix(1);
    if (s.empty()) return false;
    auto r = std::from_chars(s.data(), s.data() + s.size(), out);
    return r.ec == std::errc() && r.ptr == s.data() + s.size();
}

inline bool parse_i64(std::string_view s, std::int64_t& out) {
    if (!s.empty() && s[0] == '+') s.remove_prefix(1);
    if (s.empty()) return false;
    auto r = std::from_chars(s.data(), s.data() + s.size(), out);
    return r.ec == std::errc() && r.ptr == s.data() + s.size();
}

// Accepts what printf("%g") and friends write, including nan / inf and a leading '+'.
inline bool parse_double(std::string_view s, double& out) {
    if (!s.empty() && s[0] == '+') s.remove_prefix(1);
    if (s.empty()) return false;
    auto r = parse_decimal(s.data(), s.data() + s.size(), out);
    return r.error == std::errc() && r.end == s.data() + s.size();
}

// Parses straight to float, so that the shortest decimal a writer printed for a float gives that float back
// exactly (going through double could round twice). Values beyond the float range become +-inf or 0.
inline bool parse_float(std::string_view s, float& out) {
    if (!s.empty() && s[0] == '+') s.remove_prefix(1);
    if (s.empty()) return false;
    auto r = parse_decimal(s.data(), s.data() + s.size(), out);
    if (r.end != s.data() + s.size()) return false;
    if (r.error == std::errc()) return true;
    if (r.error != std::errc::result_out_of_range) return false;
    // Out of the float range: +-inf beyond it, +-0 below it (as strtof gives), decided in double where it fits.
    const bool negative = s[0] == '-';
    double d = 0.0;
    const auto wide = parse_decimal(s.data(), s.data() + s.size(), d);
    bool huge = false;
    if (wide.error == std::errc()) {
        huge = std::fabs(d) > 3.4028234663852886e38;
    } else {  // beyond double too: the exponent's sign says which way
        const std::size_t e = s.find_first_of("eE");
        huge = e != std::string_view::npos && e + 1 < s.size() && s[e + 1] != '-';
    }
    out = huge ? (negative ? -INFINITY : INFINITY) : (negative ? -0.0f : 0.0f);
    if (!huge && wide.error == std::errc()) out = static_cast<float>(d);  // a float denormal or 0
    return true;
}

inline std::string to_lower(std::string_view s) {
    std::string r(s);
    for (char& c : r) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    return r;
}

inline bool iequals(std::string_view a, std::string_view b) {
    if (a.size() != b.size()) return false;
    for (std::size_t i = 0; i < a.size(); ++i)
        if (std::tolower(static_cast<unsigned char>(a[i])) != std::tolower(static_cast<unsigned char>(b[i])))
            return false;
    return true;
}

// Quotes a token for an error message, cut short and with unprintable bytes escaped (the token may be garbage).
inline std::string quote(std::string_view s) {
    std::string r = "'";
    std::size_t n = 0;
    for (char c : s) {
        if (++n > 40) {
            r += "...";
            break;
        }
        unsigned char u = static_cast<unsigned char>(c);
        if (u >= 32 && u < 127) {
            r += c;
        } else {
            static const char* hex = "0123456789abcdef";
            r += "\\x";
            r += hex[u >> 4];
            r += hex[u & 15];
        }
    }
    return r + "'";
}

// ---- endian decoding (memcpy keeps it free of alignment and aliasing problems) ----------------------------------

inline std::uint16_t load_be16(const unsigned char* p) { return static_cast<std::uint16_t>((p[0] << 8) | p[1]); }
inline std::uint32_t load_be32(const unsigned char* p) {
    return (std::uint32_t(p[0]) << 24) | (std::uint32_t(p[1]) << 16) | (std::uint32_t(p[2]) << 8) | std::uint32_t(p[3]);
}
inline std::uint64_t load_be64(const unsigned char* p) {
    return (std::uint64_t(load_be32(p)) << 32) | load_be32(p + 4);
}
inline std::uint16_t load_le16(const unsigned char* p) { return static_cast<std::uint16_t>(p[0] | (p[1] << 8)); }
inline std::uint32_t load_le32(const unsigned char* p) {
    return std::uint32_t(p[0]) | (std::uint32_t(p[1]) << 8) | (std::uint32_t(p[2]) << 16) | (std::uint32_t(p[3]) << 24);
}
inline std::uint64_t load_le64(const unsigned char* p) {
    return std::uint64_t(load_le32(p)) | (std::uint64_t(load_le32(p + 4)) << 32);
}
inline float bits_to_float(std::uint32_t u) {
    float f;
    std::memcpy(&f, &u, 4);
    return f;
}
inline double bits_to_double(std::uint64_t u) {
    double d;
    std::memcpy(&d, &u, 8);
    return d;
}
inline std::uint32_t float_to_bits(float f) {
    std::uint32_t u;
    std::memcpy(&u, &f, 4);
    return u;
}

// Scalar element types common to VTK and PLY.
enum class ScalarType { i8, u8, i16, u16, i32, u32, i64, u64, f32, f64 };

inline std::size_t scalar_size(ScalarType t) {
    switch (t) {
        case ScalarType::i8:
        case ScalarType::u8: return 1;
        case ScalarType::i16:
        case ScalarType::u16: return 2;
        case ScalarType::i32:
        case ScalarType::u32:
        case ScalarType::f32: return 4;
        default: return 8;
    }
}

inline bool scalar_is_integer(ScalarType t) { return t != ScalarType::f32 && t != ScalarType::f64; }

// One spelling of a scalar type in a format's headers ("float", "Float32", "uchar", "vtktypeint64").
struct ScalarTypeName {
    const char* name;
    ScalarType type;
};

// Looks `name` up in a format's table of type names (ignoring case where the format does); false when absent.
template <std::size_t N>
bool find_scalar_type(const ScalarTypeName (&table)[N], std::string_view name, bool ignore_case, ScalarType& type) {
    for (const auto& entry : table)
        if (ignore_case ? iequals(name, entry.name) : name == entry.name) {
            type = entry.type;
            return true;
        }
    return false;
}

// Decodes one binary value of type t at p (which must hold scalar_size(t) bytes) as a double.
inline double decode_scalar(const unsigned char* p, ScalarType t, bool big_endian) {
    switch (t) {
        case ScalarType::i8: return static_cast<std::int8_t>(p[0]);
        case ScalarType::u8: return p[0];
        case ScalarType::i16: return static_cast<std::int16_t>(big_endian ? load_be16(p) : load_le16(p));
        case ScalarType::u16: return big_endian ? load_be16(p) : load_le16(p);
        case ScalarType::i32: return static_cast<std::int32_t>(big_endian ? load_be32(p) : load_le32(p));
        case ScalarType::u32: return big_endian ? load_be32(p) : load_le32(p);
        case ScalarType::i64: return static_cast<double>(static_cast<std::int64_t>(big_endian ? load_be64(p) : load_le64(p)));
        case ScalarType::u64: return static_cast<double>(big_endian ? load_be64(p) : load_le64(p));
        case ScalarType::f32: return bits_to_float(big_endian ? load_be32(p) : load_le32(p));
        case ScalarType::f64: return bits_to_double(big_endian ? load_be64(p) : load_le64(p));
    }
    return 0.0;
}

// Converts n values of type t at p (n * scalar_size(t) bytes, any alignment) to float. The switch sits outside the
// loops so that the common float32 cases stay tight.
inline void decode_to_float(const unsigned char* p, std::size_t n, ScalarType t, bool big_endian, float* out) {
    switch (t) {
        case ScalarType::f32:
            if (big_endian)
                for (std::size_t i = 0; i < n; ++i) out[i] = bits_to_float(load_be32(p + 4 * i));
            else
                for (std::size_t i = 0; i < n; ++i) out[i] = bits_to_float(load_le32(p + 4 * i));
            break;
        case ScalarType::f64:
            for (std::size_t i = 0; i < n; ++i)
                out[i] = static_cast<float>(bits_to_double(big_endian ? load_be64(p + 8 * i) : load_le64(p + 8 * i)));
            break;
        default: {
            const std::size_t size = scalar_size(t);
            for (std::size_t i = 0; i < n; ++i) out[i] = static_cast<float>(decode_scalar(p + size * i, t, big_endian));
        }
    }
}

// ---- cursor ------------------------------------------------------------------------------------------------

// A read position in a byte buffer. Every read is checked against the end first; text helpers never look past it.
class Cursor {
public:
    explicit Cursor(const Source& source) : src_(source) {}

    const Source& source() const { return src_; }
    std::size_t pos() const { return pos_; }
    std::size_t size() const { return src_.size; }
    std::size_t remaining() const { return src_.size - pos_; }
    bool at_end() const { return pos_ >= src_.size; }
    const unsigned char* here() const { return src_.data + pos_; }
    void seek(std::size_t pos) { pos_ = pos < src_.size ? pos : src_.size; }

    // "byte 123" or "byte 123 of the decompressed data".
    std::string where(std::size_t pos) const {
        return "byte " + std::to_string(pos) + (src_.decompressed ? " of the decompressed data" : "");
    }
    std::string where() const { return where(pos_); }

    [[noreturn]] void fail(const std::string& what) const { io_detail::fail(src_.path, what); }

    // Ensures n bytes are left for `what`; the message distinguishes a count the whole file could never hold
    // (a wrong count) from data that stops early (a truncated file).
    void require(std::uint64_t n, const std::string& what) const {
        if (n <= remaining()) return;
        if (n > src_.size)
            fail(what + " needs " + std::to_string(n) + " bytes but the " +
                 (src_.decompressed ? "decompressed data has" : "file has") + " only " + std::to_string(src_.size) +
                 " (a wrong count, or truncated at " + where(src_.size) + ")");
        fail("truncated at " + where(src_.size) + ": " + what + " needs " + std::to_string(n) + " bytes from " +
             where() + ", only " + std::to_string(remaining()) + " remain");
    }

    const unsigned char* take(std::uint64_t n, const std::string& what) {
        require(n, what);
        const unsigned char* p = here();
        pos_ += static_cast<std::size_t>(n);
        return p;
    }

    std::uint8_t u8(const char* what) { return *take(1, what); }
    std::uint16_t be_u16(const char* what) { return load_be16(take(2, what)); }
    std::int32_t be_i32(const char* what) { return static_cast<std::int32_t>(load_be32(take(4, what))); }

    // ---- text ----
    static bool is_space(unsigned char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\n' || c == '\f' || c == '\v'; }

    void skip_space() {
        while (pos_ < src_.size && is_space(src_.data[pos_])) ++pos_;
    }

    // Next whitespace-separated token (empty at the end of the buffer).
    std::string_view token() {
        skip_space();
        std::size_t start = pos_;
        while (pos_ < src_.size && !is_space(src_.data[pos_])) ++pos_;
        return view(start, pos_);
    }

    // The rest of the current line without its line break; the cursor moves past the '\n'.
    std::string_view line() {
        std::size_t start = pos_;
        while (pos_ < src_.size && src_.data[pos_] != '\n') ++pos_;
        std::size_t end = pos_;
        if (pos_ < src_.size) ++pos_;  // the '\n'
        if (end > start && src_.data[end - 1] == '\r') --end;
        return view(start, end);
    }

    // True when the text at the cursor starts with `word` (case-insensitive) followed by a space or the end.
    bool starts_with_word(std::string_view word) const {
        if (remaining() < word.size()) return false;
        if (!iequals(view(pos_, pos_ + word.size()), word)) return false;
        return remaining() == word.size() || is_space(src_.data[pos_ + word.size()]);
    }

    std::string_view view(std::size_t begin, std::size_t end) const {
        return std::string_view(reinterpret_cast<const char*>(src_.data) + begin, end - begin);
    }

private:
    Source src_;
    std::size_t pos_ = 0;
};

// A run of bytes [begin, end) of a source, such as the character data of an XML element.
struct TextRange {
    std::size_t begin = 0, end = 0;
};

// Splits a line into whitespace-separated tokens, at most max_tokens of them (keyword lines need a handful; the
// cap keeps a binary blob mistaken for a line from turning into millions of tokens).
inline std::vector<std::string_view> split_tokens(std::string_view line, std::size_t max_tokens = SIZE_MAX) {
    std::vector<std::string_view> out;
    std::size_t i = 0;
    while (i < line.size() && out.size() < max_tokens) {
        while (i < line.size() && Cursor::is_space(static_cast<unsigned char>(line[i]))) ++i;
        std::size_t start = i;
        while (i < line.size() && !Cursor::is_space(static_cast<unsigned char>(line[i]))) ++i;
        if (i > start) out.push_back(line.substr(start, i - start));
    }
    return out;
}

}  // namespace io_detail
}  // namespace meniscus
