// Classic Houdini BGEO particle reader ("BgeoV", version 5, the layout Partio reads and writes).
//
// Layout, all big-endian: "Bgeo" 'V' int32 version; int32 counts nPoints, nPrims, nPointGroups, nPrimGroups,
// nPointAttrib, nVertexAttrib, nPrimAttrib, nAttrib; nPointAttrib attribute definitions (uint16 name length, name,
// uint16 component count, int32 type, then the default values: one 32-bit word per component for float (0), int (1)
// and vector (5); for index/string tables (4) an int32 string count and that many uint16-length strings); then per
// point 4 floats (x, y, z, w) followed by every attribute's 32-bit words in definition order. Groups, primitives and
// detail attributes follow the points; particles need none of them, so they are not read.
#include "io/io_util.h"

namespace meniscus {
namespace io_detail {
namespace {

struct BgeoAttribute {
    std::string name;
    int type = 0;          // Houdini type code
    std::size_t size = 0;  // 32-bit words per point
    bool keep = false;     // float, int and vector attributes are kept; index tables are skipped
};

const char* bgeo_type_name(int type) {
    switch (type) {
        case 0: return "float";
        case 1: return "int";
        case 2: return "string";
        case 4: return "index";
        case 5: return "vector";
        default: return "unknown";
    }
}

[[noreturn]] void unsupported(const Cursor& c, const std::string& what) {
    c.fail("unsupported BGEO variant: " + what + "; supported are the classic 'BgeoV' version 5 format (as written "
           "by Partio or Houdini's .bhclassic) and Houdini's JSON geometry (binary 0x7f 'NSJb' .bgeo, ASCII .geo)");
}

// The magic and version; anything but classic version 5 is refused by name.
void read_magic(Cursor& c) {
    if (c.remaining() >= 4 && std::memcmp(c.here(), "\x7fNSJ", 4) == 0)
        unsupported(c, "a binary JSON header that is neither 'NSJb' nor 'bJSN'");
    if (c.remaining() >= 9 && std::memcmp(c.here(), "PGEOMETRY", 9) == 0) unsupported(c, "ASCII .geo file");
    const unsigned char* magic = c.take(4, "BGEO magic");
    if (std::memcmp(magic, "Bgeo", 4) != 0) c.fail("not a BGEO file: it does not start with 'Bgeo'");
    unsigned char version_char = c.u8("BGEO version letter");
    if (version_char != 'V') unsupported(c, "version letter " + quote(std::string(1, static_cast<char>(version_char))) + " instead of 'V'");
    std::int32_t version = c.be_i32("BGEO version");
    if (version != 5) unsupported(c, "version " + std::to_string(version));
}

// The point attribute definitions; `words_per_point` gets each one's size added.
std::vector<BgeoAttribute> read_definitions(Cursor& c, std::uint64_t count, std::uint64_t& words_per_point) {
    // A definition takes at least 8 bytes (name length, size, type): bound the count before reserving.
    if (count * 8 > c.remaining())
        c.fail("point attribute count " + std::to_string(count) + " needs at least " + std::to_string(count * 8) +
               " bytes of definitions, only " + std::to_string(c.remaining()) + " remain after " + c.where());
    std::vector<BgeoAttribute> attributes;
    attributes.reserve(static_cast<std::size_t>(count));
    for (std::uint64_t k = 0; k < count; ++k) {
        std::size_t def_pos = c.pos();
        BgeoAttribute a;
        std::uint16_t name_length = c.be_u16("attribute name length");
        const unsigned char* name = c.take(name_length, "attribute name");
        a.name.assign(reinterpret_cast<const char*>(name), name_length);
        a.size = c.be_u16("attribute size");
        a.type = c.be_i32("attribute type");
        if (a.type == 0 || a.type == 1 || a.type == 5) {
            c.take(std::uint64_t(4) * a.size, "default values of attribute " + quote(a.name));
            a.keep = a.size > 0;
        } else if (a.type == 4) {
            // Index attribute: a table of strings, then one index per point. Strings have no float meaning: skip.
            std::size_t pos = c.pos();
            std::int32_t strings = c.be_i32("index attribute string count");
            if (strings < 0 || std::uint64_t(strings) * 2 > c.remaining())
                c.fail("bad string count " + std::to_string(strings) + " of index attribute " + quote(a.name) + " at " + c.where(pos));
            for (std::int32_t s = 0; s < strings; ++s) c.take(c.be_u16("index string length"), "index string");
        } else {
            unsupported(c, "attribute " + quote(a.name) + " at " + c.where(def_pos) + " has type " + std::to_string(a.type) + " (" +
                               bgeo_type_name(a.type) + "); supported are float (0), int (1), vector (5) and index (4)");
        }
        words_per_point += a.size;
        attributes.push_back(std::move(a));
    }
    return attributes;
}

// Attribute `a`, `offset` words into each point record of `words_per_point` words.
Attribute read_point_attribute(const BgeoAttribute& a, const unsigned char* data, std::size_t n, std::uint64_t words_per_point,
                               std::size_t offset) {
    Attribute out;
    out.name = a.name;
    out.components = static_cast<int>(a.size);
    out.integral = a.type == 1;  // BGEO attribute types: 0 float, 1 int, 5 vector
    out.values.resize(n * a.size);
    for (std::size_t i = 0; i < n; ++i) {
        const unsigned char* p = data + (i * words_per_point + offset) * 4;
        for (std::size_t k = 0; k < a.size; ++k) {
            std::uint32_t word = load_be32(p + 4 * k);
            out.values[i * a.size + k] = a.type == 1 ? static_cast<float>(static_cast<std::int32_t>(word)) : bits_to_float(word);
        }
    }
    return out;
}

}  // namespace

ParticleData read_bgeo_particles(const Source& source) {
    Cursor c(source);
    read_magic(c);
    static const char* count_names[] = {"point count",           "primitive count",        "point group count",
                                        "primitive group count", "point attribute count",  "vertex attribute count",
                                        "primitive attribute count", "detail attribute count"};
    std::int64_t counts[8];
    for (int i = 0; i < 8; ++i) {
        std::size_t pos = c.pos();
        counts[i] = c.be_i32(count_names[i]);
        if (counts[i] < 0) c.fail("negative " + std::string(count_names[i]) + " " + std::to_string(counts[i]) + " at " + c.where(pos));
    }
    const std::uint64_t num_points = static_cast<std::uint64_t>(counts[0]);
    std::uint64_t words_per_point = 4;  // x y z w
    const std::vector<BgeoAttribute> attributes = read_definitions(c, static_cast<std::uint64_t>(counts[4]), words_per_point);

    std::uint64_t bytes = 0;
    if (!checked_mul(num_points, words_per_point * 4, bytes)) c.fail("point count " + std::to_string(num_points) + " is impossibly large");
    c.require(bytes, "point count " + std::to_string(num_points) + " (" + std::to_string(words_per_point * 4) + " bytes per point)");
    const unsigned char* data = c.take(bytes, "point data");

    ParticleData result;
    const std::size_t n = static_cast<std::size_t>(num_points);
    result.positions.resize(3 * n);
    for (std::size_t i = 0; i < n; ++i) {
        const unsigned char* p = data + i * words_per_point * 4;
        for (int k = 0; k < 3; ++k) result.positions[3 * i + k] = bits_to_float(load_be32(p + 4 * k));
    }
    std::size_t offset = 4;  // in words, after x y z w
    for (const auto& a : attributes) {
        if (a.keep) result.attributes.push_back(read_point_attribute(a, data, n, words_per_point, offset));
        offset += a.size;
    }
    return result;
}

}  // namespace io_detail
}  // namespace meniscus
