// OpenVDB point data grids (Tree_ptdataidx32_5_4_3), read without the OpenVDB library: the file header, the grid
// descriptors (other grids are skipped by their end offsets), the transform, the 5-4-3 tree topology and the
// multi-pass leaf buffers with their paged, Blosc- or zlib-compressed attribute arrays. Layout notes in
// docs/formats.md ("OpenVDB points").
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <memory>
#include <string>
#include <vector>

#include "io/blosc.h"
#include "io/formats/mantaflow.h"
#include "io/io_util.h"

namespace meniscus {
namespace io_detail {

namespace {

constexpr std::uint32_t kCompressZip = 0x1, kCompressActiveMask = 0x2, kCompressBlosc = 0x4;
constexpr std::uint32_t kMinVersion = 222;       // node mask compression (OpenVDB 3.0, 2014)
constexpr std::uint32_t kMultiPassVersion = 224;  // point data grids
constexpr std::size_t kLeafVoxels = 512;
constexpr std::uint32_t kMaxStride = 1u << 16;  // values per point of one array: far above any attribute OpenVDB writes

float half_to_float(std::uint16_t h) {
    const std::uint32_t sign = std::uint32_t(h & 0x8000u) << 16;
    std::uint32_t exponent = (h >> 10) & 0x1fu, mantissa = h & 0x3ffu;
    if (exponent == 0) {
        if (mantissa == 0) return bits_to_float(sign);
        float f = std::ldexp(static_cast<float>(mantissa), -24);  // subnormal
        return sign ? -f : f;
    }
    if (exponent == 31) return bits_to_float(sign | 0x7f800000u | (mantissa << 13));
    return bits_to_float(sign | ((exponent + 112) << 23) | (mantissa << 13));
}

struct Leaf {
    std::array<std::int32_t, 3> origin;
    std::array<std::uint32_t, kLeafVoxels> end_offsets{};  // points of voxel v: [end[v-1], end[v])
    std::uint16_t voxel_bytes = 0;
    std::size_t points() const { return end_offsets[kLeafVoxels - 1]; }
};

// What the attribute arrays of the leaves hold (the descriptor), and how one leaf's array is stored.
struct AttributeType {
    std::string name, type, codec;
};
struct ArrayHeader {
    std::uint64_t bytes = 0;
    bool uniform = false, paged = false;
    std::uint32_t size = 0, stride = 1;
};
struct Page {
    std::int64_t compressed = 0, uncompressed = 0;  // compressed <= 0: stored
    std::vector<unsigned char> data;
};
struct Handle {
    std::size_t page = 0, offset = 0;
};

// One attribute value type with its codec: components per value, bytes per component on disk, and how a stored
// component becomes a float. Unknown pairs are skipped (groups, strings, matrices).
struct Storage {
    int components = 0;
    std::size_t bytes = 0;
    enum Kind { f32, f64, f16, i8, u8, i16, i32, i64, fixed8, fixed16 } kind = f32;
    bool position_range = false;  // fixed point: stored / max - 0.5 (a voxel-local position), else stored / max
    bool integral = false;
};

bool storage_of(const std::string& type, const std::string& codec, Storage& s) {
    const bool vec3 = type.rfind("vec3", 0) == 0;
    const std::string scalar = vec3 ? type.substr(4) : type;
    s.components = vec3 ? 3 : 1;
    if (codec == "null") {
        if (scalar == "s" || scalar == "float") s.kind = Storage::f32, s.bytes = 4;
        else if (scalar == "d" || scalar == "double") s.kind = Storage::f64, s.bytes = 8;
        else if (scalar == "i" || scalar == "int32") s.kind = Storage::i32, s.bytes = 4, s.integral = true;
        else if (scalar == "int64") s.kind = Storage::i64, s.bytes = 8, s.integral = true;
        else if (scalar == "int16") s.kind = Storage::i16, s.bytes = 2, s.integral = true;
        else if (scalar == "int8") s.kind = Storage::i8, s.bytes = 1, s.integral = true;
        else if (scalar == "bool" || scalar == "uint8") s.kind = Storage::u8, s.bytes = 1, s.integral = true;
        else return false;
        return true;
    }
    if (codec == "trnc") {
        if (scalar == "s" || scalar == "float") s.kind = Storage::f16, s.bytes = 2;
        else if (scalar == "d" || scalar == "double") s.kind = Storage::f32, s.bytes = 4;
        else return false;
        return true;
    }
    if (codec == "fxpt8" || codec == "fxpt16" || codec == "ufxpt8" || codec == "ufxpt16") {
        if (scalar != "s" && scalar != "float" && scalar != "d" && scalar != "double") return false;
        const bool eight = codec.find('8') != std::string::npos;
        s.kind = eight ? Storage::fixed8 : Storage::fixed16;
        s.bytes = eight ? 1 : 2;
        s.position_range = codec[0] == 'f';
        return true;
    }
    return false;
}

double decode_component(const unsigned char* p, const Storage& s) {
    switch (s.kind) {
        case Storage::f32: return bits_to_float(load_le32(p));
        case Storage::f64: return bits_to_double(load_le64(p));
        case Storage::f16: return half_to_float(load_le16(p));
        case Storage::i8: return static_cast<std::int8_t>(p[0]);
        case Storage::u8: return p[0];
        case Storage::i16: return static_cast<std::int16_t>(load_le16(p));
        case Storage::i32: return static_cast<std::int32_t>(load_le32(p));
        case Storage::i64: return static_cast<double>(static_cast<std::int64_t>(load_le64(p)));
        case Storage::fixed8: return p[0] / 255.0 - (s.position_range ? 0.5 : 0.0);
        case Storage::fixed16: return load_le16(p) / 65535.0 - (s.position_range ? 0.5 : 0.0);
    }
    return 0.0;
}

// An index -> world map (OpenVDB's linear maps): world = index * scale + translation, or the 4x4 affine matrix
// (row vectors, as OpenVDB stores it).
struct IndexToWorld {
    std::array<double, 16> m{1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};
    std::array<double, 3> apply(double x, double y, double z) const {
        return {x * m[0] + y * m[4] + z * m[8] + m[12], x * m[1] + y * m[5] + z * m[9] + m[13],
                x * m[2] + y * m[6] + z * m[10] + m[14]};
    }
};

class VdbReader {
public:
    explicit VdbReader(const Source& source) : c_(source) {}

    ParticleData read();

private:
    Cursor c_;
    std::uint32_t version_ = 0;
    std::uint32_t compression_ = 0;
    std::vector<unsigned char> scratch_;  // internal node values: read and dropped

    std::uint32_t u32(const char* what) { return load_le32(c_.take(4, what)); }
    std::int32_t i32(const char* what) { return static_cast<std::int32_t>(u32(what)); }
    std::int64_t i64(const char* what) { return static_cast<std::int64_t>(load_le64(c_.take(8, what))); }
    std::string string(const char* what) {
        const std::size_t at = c_.pos();
        const std::uint32_t n = u32(what);
        if (n > c_.remaining()) c_.fail(std::string(what) + " at " + c_.where(at) + " claims " + std::to_string(n) + " bytes, more than the file has left");
        const unsigned char* p = c_.take(n, what);
        return std::string(reinterpret_cast<const char*>(p), n);
    }
    void skip_metadata(const char* what);
    IndexToWorld read_transform();
    void read_data(unsigned char* out, std::size_t bytes, const std::string& what);
    void skip_compressed_values(std::size_t values, std::size_t value_bytes, std::size_t mask_bytes, const std::string& what);
    void read_internal_topology(int log2dim, std::array<std::int32_t, 3> origin, std::vector<Leaf>& leaves);
    ParticleData read_point_grid(const std::string& name, std::uint64_t block_pos);
};

void VdbReader::skip_metadata(const char* what) {
    const std::size_t at = c_.pos();
    const std::int32_t count = i32(what);
    if (count < 0 || static_cast<std::uint64_t>(count) > c_.remaining() / 12)
        c_.fail(std::string(what) + ": " + std::to_string(count) + " entries at " + c_.where(at) + " cannot be in the file");
    for (std::int32_t k = 0; k < count; ++k) {
        string("a metadata name");
        string("a metadata type");
        const std::uint32_t size = u32("a metadata size");
        c_.take(size, "a metadata value");
    }
}

IndexToWorld VdbReader::read_transform() {
    const std::size_t at = c_.pos();
    const std::string type = string("the transform's map type");
    auto vec3 = [&](const char* what) {
        std::array<double, 3> v;
        for (double& d : v) d = bits_to_double(load_le64(c_.take(8, what)));
        return v;
    };
    IndexToWorld t;
    if (type == "UniformScaleMap" || type == "ScaleMap" || type == "UniformScaleTranslateMap" || type == "ScaleTranslateMap" ||
        type == "TranslationMap") {
        const bool translated = type.find("Translat") != std::string::npos;
        const auto translation = translated ? vec3("the translation") : std::array<double, 3>{0, 0, 0};
        std::array<double, 3> scale{1, 1, 1};
        if (type != "TranslationMap") {
            scale = vec3("the scale");
            c_.take(4 * 24, "the scale map's derived values");  // voxel size, inverse, inverse square, inverse twice
        }
        for (int k = 0; k < 3; ++k) t.m[5 * k] = scale[k], t.m[12 + k] = translation[k];
    } else if (type == "AffineMap") {
        for (double& d : t.m) d = bits_to_double(load_le64(c_.take(8, "the affine matrix")));
    } else {
        c_.fail("transform map " + quote(type) + " at " + c_.where(at) +
                " is not supported (linear maps are: UniformScaleMap, ScaleMap, their Translate forms, TranslationMap, AffineMap)");
    }
    for (double d : t.m)
        if (!std::isfinite(d)) c_.fail("the grid's transform at " + c_.where(at) + " is not finite");
    return t;
}

// OpenVDB's readData: an int64 size (<= 0: that many stored bytes), then a Blosc frame or a zlib stream by the
// grid's compression flags.
void VdbReader::read_data(unsigned char* out, std::size_t bytes, const std::string& what) {
    if (!(compression_ & (kCompressBlosc | kCompressZip))) {
        const unsigned char* in = c_.take(bytes, what);
        if (bytes) std::memcpy(out, in, bytes);  // out may be null for no values
        return;
    }
    const std::size_t at = c_.pos();
    const std::int64_t size = i64("a compressed block's size");
    if (size <= 0) {
        if (static_cast<std::uint64_t>(-size) != bytes)
            c_.fail(what + ": a stored block of " + std::to_string(-size) + " bytes at " + c_.where(at) + " where " +
                    std::to_string(bytes) + " are expected");
        const unsigned char* in = c_.take(bytes, what);
        if (bytes) std::memcpy(out, in, bytes);
        return;
    }
    const unsigned char* in = c_.take(static_cast<std::uint64_t>(size), what);
    if (bytes > max_inflated_size(static_cast<std::uint64_t>(size)))
        c_.fail(what + ": " + std::to_string(bytes) + " bytes from a block of " + std::to_string(size) + " at " + c_.where(at) +
                " (beyond the decompression cap)");
    const std::string where = what + " (block at " + c_.where(at) + ")";
    if (compression_ & kCompressBlosc)
        blosc_decompress(c_.source().path, in, static_cast<std::size_t>(size), out, bytes, where);
    else
        inflate_exact(c_.source().path, in, static_cast<std::size_t>(size), out, bytes, 15, where);
}

// OpenVDB's readCompressedValues for a node of `values` values: a metadata byte, up to two inactive values, an
// optional selection mask, then the (active, with mask compression) values.
void VdbReader::skip_compressed_values(std::size_t values, std::size_t value_bytes, std::size_t mask_bytes, const std::string& what) {
    const std::size_t at = c_.pos();
    const unsigned metadata = c_.u8("a node's value metadata");
    if (metadata > 6) c_.fail(what + ": value metadata " + std::to_string(metadata) + " at " + c_.where(at) + " is not 0-6");
    if (metadata == 2 || metadata == 4 || metadata == 5) c_.take(value_bytes * (metadata == 5 ? 2 : 1), "inactive values");
    if (metadata == 3 || metadata == 4 || metadata == 5) c_.take(mask_bytes, "a selection mask");
    // With mask compression only the active values are stored; the caller's value mask says how many.
    scratch_.resize(values * value_bytes);
    read_data(scratch_.data(), values * value_bytes, what);
}

std::size_t count_bits(const unsigned char* mask, std::size_t bytes) {
    std::size_t n = 0;
    for (std::size_t i = 0; i < bytes; ++i)
        for (unsigned b = mask[i]; b; b &= b - 1) ++n;
    return n;
}

// Internal nodes of the 5-4-3 tree: 32^3 (log2dim 5) and 16^3 (4) children, then 8^3 leaves.
void VdbReader::read_internal_topology(int log2dim, std::array<std::int32_t, 3> origin, std::vector<Leaf>& leaves) {
    const std::size_t values = std::size_t(1) << (3 * log2dim), mask_bytes = values / 8;
    const int child_total = log2dim == 5 ? 7 : 3;  // log2 of a child's extent in voxels
    const unsigned char* child_mask = c_.take(mask_bytes, "a node's child mask");
    const unsigned char* value_mask = c_.take(mask_bytes, "a node's value mask");
    const std::size_t active = count_bits(value_mask, mask_bytes);
    const unsigned metadata = c_.remaining() ? c_.here()[0] : 0;  // read again by skip_compressed_values
    const std::size_t stored = (compression_ & kCompressActiveMask) && metadata != 6 ? active : values;
    skip_compressed_values(stored, 4, mask_bytes, "an internal node's values");
    for (std::size_t i = 0; i < values; ++i) {
        if (!(child_mask[i >> 3] & (1u << (i & 7)))) continue;
        const std::array<std::int32_t, 3> child_origin{
            origin[0] + (static_cast<std::int32_t>(i >> (2 * log2dim)) << child_total),
            origin[1] + (static_cast<std::int32_t>((i >> log2dim) & ((1u << log2dim) - 1)) << child_total),
            origin[2] + (static_cast<std::int32_t>(i & ((1u << log2dim) - 1)) << child_total)};
        if (log2dim == 5) {
            read_internal_topology(4, child_origin, leaves);
        } else {
            c_.take(kLeafVoxels / 8, "a leaf's value mask");
            if (leaves.size() >= c_.size()) c_.fail("more leaves than the file has bytes");
            leaves.push_back(Leaf{child_origin, {}, 0});
        }
    }
}

ParticleData VdbReader::read_point_grid(const std::string& name, std::uint64_t block_pos) {
    const std::string grid = "point grid " + quote(name);
    if (version_ < kMultiPassVersion)
        c_.fail(grid + ": OpenVDB file version " + std::to_string(version_) + " has no multi-pass point data (224 and later do)");
    compression_ = u32("the grid's compression flags");
    skip_metadata("the grid's metadata");
    const IndexToWorld transform = read_transform();

    // Topology: one buffer, the root's background, tiles and children (sorted by origin, as the buffers follow).
    const std::size_t at = c_.pos();
    const std::int32_t buffers = i32("the tree's buffer count");
    if (buffers != 1) c_.fail(grid + ": " + std::to_string(buffers) + " buffers per node at " + c_.where(at) + " (OpenVDB writes 1)");
    c_.take(4, "the background value");
    const std::uint32_t tiles = u32("the root's tile count"), children = u32("the root's child count");
    if (tiles > c_.remaining() / 17 || children > c_.remaining() / 12)
        c_.fail(grid + ": " + std::to_string(tiles) + " tiles and " + std::to_string(children) + " children at " + c_.where(at + 8) +
                " cannot be in the file");
    c_.take(std::uint64_t(tiles) * 17, "the root's tiles");
    std::vector<std::pair<std::array<std::int32_t, 3>, std::vector<Leaf>>> roots;
    for (std::uint32_t k = 0; k < children; ++k) {
        std::array<std::int32_t, 3> origin;
        for (auto& o : origin) o = i32("a root child's origin");
        for (auto o : origin)
            if (o % 4096 != 0) c_.fail(grid + ": root child origin " + std::to_string(o) + " at " + c_.where() + " is not on the 4096-voxel grid");
        roots.push_back({origin, {}});
        read_internal_topology(5, origin, roots.back().second);
    }
    std::stable_sort(roots.begin(), roots.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
    std::vector<Leaf> leaves;
    for (auto& r : roots) leaves.insert(leaves.end(), r.second.begin(), r.second.end());
    if (c_.pos() != block_pos)
        c_.fail(grid + ": the topology ends at " + c_.where() + " but the grid's buffers start at byte " + std::to_string(block_pos));

    // Buffers, pass by pass over all leaves (OpenVDB's PointDataLeafNode::readBuffers).
    const std::size_t passes_at = c_.pos();
    const unsigned passes = load_le16(c_.take(2, "the pass count"));
    // An empty grid (no liquid yet) writes no passes; without leaves no descriptor is read, whatever the passes say.
    if (leaves.empty()) return ParticleData{};
    if (passes < 4 || passes % 2 != 0) c_.fail(grid + ": pass count " + std::to_string(passes) + " at " + c_.where(passes_at) + " is not 4 + 2 per attribute");
    const std::size_t attributes = (passes - 4) / 2;
    for (Leaf& leaf : leaves) leaf.voxel_bytes = load_le16(c_.take(2, "a leaf's voxel buffer size"));

    std::vector<AttributeType> descriptor;
    bool shared = false;
    std::vector<std::vector<ArrayHeader>> headers(leaves.size());
    for (std::size_t l = 0; l < leaves.size(); ++l) {
        if (!shared) {
            const std::size_t header_at = c_.pos();
            const unsigned header = c_.u8("a leaf's descriptor flags");
            if (header > 3) c_.fail(grid + ": descriptor flags " + std::to_string(header) + " at " + c_.where(header_at) + " are not 0-3");
            const std::uint64_t count = load_le64(c_.take(8, "the attribute count"));
            if (count != attributes)
                c_.fail(grid + ": " + std::to_string(count) + " attributes at " + c_.where(header_at + 1) + " but " +
                        std::to_string(passes) + " passes (for " + std::to_string(attributes) + ")");
            std::vector<AttributeType> types(attributes);
            for (auto& t : types) {
                t.type = string("an attribute type");
                t.codec = string("an attribute codec");
            }
            for (std::size_t k = 0; k < attributes; ++k) {
                const std::string attribute = string("an attribute name");
                const std::uint64_t index = load_le64(c_.take(8, "an attribute index"));
                if (index >= attributes) c_.fail(grid + ": attribute " + quote(attribute) + " has index " + std::to_string(index) + " of " + std::to_string(attributes));
                types[index].name = attribute;
            }
            const std::uint64_t groups = load_le64(c_.take(8, "the group count"));
            if (groups > c_.remaining() / 12) c_.fail(grid + ": " + std::to_string(groups) + " groups cannot be in the file");
            for (std::uint64_t g = 0; g < groups; ++g) {
                string("a group name");
                c_.take(8, "a group index");
            }
            skip_metadata("the attributes' metadata");
            if (header & 2) c_.take(load_le64(c_.take(8, "a skip size")), "bytes to skip");
            if (!descriptor.empty() && (descriptor.size() != types.size() || !std::equal(descriptor.begin(), descriptor.end(), types.begin(), [](const auto& a, const auto& b) {
                                            return a.name == b.name && a.type == b.type && a.codec == b.codec;
                                        })))
                c_.fail(grid + ": leaves with different attributes are not supported");
            descriptor = types;
            shared = header & 1;
        }
        for (std::size_t a = 0; a < attributes; ++a) {
            ArrayHeader h;
            const std::size_t header_at = c_.pos();
            h.bytes = load_le64(c_.take(8, "an attribute array's size"));
            const unsigned flags = c_.u8("an attribute array's flags");
            const unsigned serialization = c_.u8("an attribute array's serialization flags");
            h.size = u32("an attribute array's length");
            if (serialization & 1) h.stride = u32("an attribute array's stride");
            if (serialization >= 0x10 || (flags & 0x20) || h.bytes < 6 || h.stride == 0)
                c_.fail(grid + ": attribute " + quote(descriptor[a].name) + " of leaf " + std::to_string(l) + " at " + c_.where(header_at) +
                        " has flags " + std::to_string(flags) + "/" + std::to_string(serialization) + " and " + std::to_string(h.bytes) +
                        " bytes, which OpenVDB does not write");
            // Values are read with leaf 0's stride: another stride in a later leaf would read past its data.
            if (h.stride > kMaxStride || (l > 0 && h.stride != headers[0][a].stride))
                c_.fail(grid + ": attribute " + quote(descriptor[a].name) + " of leaf " + std::to_string(l) + " at " + c_.where(header_at) +
                        " has stride " + std::to_string(h.stride) + (l > 0 ? " where leaf 0 has " + std::to_string(headers[0][a].stride) : std::string()));
            h.bytes -= 6;
            h.uniform = serialization & 2;
            h.paged = serialization & 8;
            headers[l].push_back(h);
        }
    }

    // Attribute sizes: paged arrays take their bytes from shared pages whose headers come here.
    std::vector<std::vector<Page>> pages(attributes);
    std::vector<std::vector<Handle>> handles(attributes, std::vector<Handle>(leaves.size()));
    std::vector<std::int64_t> page_fill(attributes, 0);
    for (std::size_t a = 0; a < attributes; ++a) {
        for (std::size_t l = 0; l < leaves.size(); ++l) {
            const ArrayHeader& h = headers[l][a];
            if (!h.paged) continue;
            if (pages[a].empty() || page_fill[a] == pages[a].back().uncompressed) {
                const std::size_t page_at = c_.pos();
                Page page;
                page.compressed = i32("a page's compressed size");
                page.uncompressed = page.compressed > 0 ? i32("a page's size") : -page.compressed;
                if (page.compressed == 0 || page.uncompressed <= 0 ||
                    static_cast<std::uint64_t>(page.uncompressed) >
                        (page.compressed > 0 ? max_inflated_size(page.compressed) : c_.size()))
                    c_.fail(grid + ": attribute " + quote(descriptor[a].name) + " has a page of " + std::to_string(page.compressed) +
                            " / " + std::to_string(page.uncompressed) + " bytes at " + c_.where(page_at));
                pages[a].push_back(std::move(page));
                page_fill[a] = 0;
            }
            if (h.bytes > static_cast<std::uint64_t>(pages[a].back().uncompressed - page_fill[a]))
                c_.fail(grid + ": attribute " + quote(descriptor[a].name) + " of leaf " + std::to_string(l) + " needs " + std::to_string(h.bytes) +
                        " bytes, its page has " + std::to_string(pages[a].back().uncompressed - page_fill[a]) + " left");
            handles[a][l] = Handle{pages[a].size() - 1, static_cast<std::size_t>(page_fill[a])};
            page_fill[a] += static_cast<std::int64_t>(h.bytes);
        }
    }

    // Voxel data: each leaf's value mask, then the end offsets of its voxels' points (Blosc or stored).
    std::size_t total = 0;
    for (std::size_t l = 0; l < leaves.size(); ++l) {
        Leaf& leaf = leaves[l];
        c_.take(kLeafVoxels / 8, "a leaf's value mask");
        const std::size_t voxels_at = c_.pos();
        const unsigned bytes = load_le16(c_.take(2, "a leaf's voxel buffer size"));
        unsigned char raw[kLeafVoxels * 4];
        if (bytes == 0xffff) {
            std::memcpy(raw, c_.take(sizeof raw, "a leaf's voxel offsets"), sizeof raw);
        } else {
            const unsigned char* in = c_.take(bytes, "a leaf's compressed voxel offsets");
            blosc_decompress(c_.source().path, in, bytes, raw, sizeof raw, grid + " leaf " + std::to_string(l) + " voxel offsets at " + c_.where(voxels_at));
        }
        std::uint32_t previous = 0;
        for (std::size_t v = 0; v < kLeafVoxels; ++v) {
            leaf.end_offsets[v] = load_le32(raw + 4 * v);
            if (leaf.end_offsets[v] < previous)
                c_.fail(grid + ": leaf " + std::to_string(l) + " has decreasing point offsets (voxel " + std::to_string(v) + ", data at " + c_.where(voxels_at) + ")");
            previous = leaf.end_offsets[v];
        }
        total += leaf.points();
        for (std::size_t a = 0; a < attributes; ++a) {
            const ArrayHeader& h = headers[l][a];
            if (!h.uniform && h.size != leaf.points())
                c_.fail(grid + ": attribute " + quote(descriptor[a].name) + " of leaf " + std::to_string(l) + " has " + std::to_string(h.size) +
                        " values for " + std::to_string(leaf.points()) + " points");
        }
    }

    // Attribute data, attribute by attribute: paged arrays read whole pages when a leaf starts one.
    std::size_t position_index = attributes;
    for (std::size_t a = 0; a < attributes; ++a)
        if (descriptor[a].name == "P") position_index = a;
    if (position_index == attributes) c_.fail(grid + " has no position attribute 'P'");
    ParticleData out;
    std::vector<Storage> storage(attributes);
    std::vector<bool> keep(attributes, false);
    for (std::size_t a = 0; a < attributes; ++a) {
        keep[a] = storage_of(descriptor[a].type, descriptor[a].codec, storage[a]);
        if (a == position_index && (!keep[a] || storage[a].components != 3))
            c_.fail(grid + ": positions of type " + quote(descriptor[a].type) + " with codec " + quote(descriptor[a].codec) + " are not supported");
    }
    std::uint64_t position_floats = 0;
    if (!checked_mul(total, 3, position_floats) || position_floats > c_.size() * kGunzipRatioCap + kGunzipSlackBytes)
        c_.fail(grid + ": " + std::to_string(total) + " points cannot come from a file of this size");
    out.positions.resize(3 * total);
    std::vector<std::size_t> attribute_slot(attributes, SIZE_MAX);
    for (std::size_t a = 0; a < attributes; ++a) {
        if (!keep[a] || a == position_index) continue;
        attribute_slot[a] = out.attributes.size();
        Attribute attr;
        attr.name = descriptor[a].name;
        attr.components = storage[a].components * static_cast<int>(headers.empty() ? 1 : headers[0][a].stride);
        attr.integral = storage[a].integral;
        // A uniform attribute stores one value for every point: bound what it expands to as the positions are bounded.
        std::uint64_t floats = 0;
        if (!checked_mul(total, static_cast<std::uint64_t>(attr.components), floats) || floats > c_.size() * kGunzipRatioCap + kGunzipSlackBytes)
            c_.fail(grid + ": attribute " + quote(attr.name) + " of " + std::to_string(attr.components) + " values for each of " +
                    std::to_string(total) + " points cannot come from a file of this size");
        attr.values.reserve(static_cast<std::size_t>(floats));
        out.attributes.push_back(std::move(attr));
    }
    for (std::size_t a = 0; a < attributes; ++a) {
        page_fill[a] = pages[a].empty() ? 0 : pages[a].back().uncompressed;  // as the size pass left the stream
        std::int64_t page_end = page_fill[a];
        std::size_t first_point = 0;
        for (std::size_t l = 0; l < leaves.size(); ++l) {
            const ArrayHeader& h = headers[l][a];
            const Leaf& leaf = leaves[l];
            const unsigned char* data = nullptr;
            std::vector<unsigned char> unpaged;
            const std::string what = grid + " attribute " + quote(descriptor[a].name) + " of leaf " + std::to_string(l);
            if (h.paged) {
                Page& page = pages[a][handles[a][l].page];
                if (page_fill[a] == page_end) {
                    const std::size_t page_at = c_.pos();
                    page.data.resize(static_cast<std::size_t>(page.uncompressed));
                    if (page.compressed > 0)
                        blosc_decompress(c_.source().path, c_.take(page.compressed, "a compressed page"), static_cast<std::size_t>(page.compressed),
                                         page.data.data(), page.data.size(), what + " (page at " + c_.where(page_at) + ")");
                    else
                        std::memcpy(page.data.data(), c_.take(page.data.size(), "a stored page"), page.data.size());
                    page_fill[a] = 0;
                    page_end = page.uncompressed;
                }
                page_fill[a] += static_cast<std::int64_t>(h.bytes);
                data = page.data.data() + handles[a][l].offset;
            } else {
                const unsigned compressed = h.uniform ? 0 : c_.u8("an attribute array's compression flag");
                const unsigned char* in = c_.take(h.bytes, "an attribute array");
                if (compressed) {
                    std::uint64_t expected = 0;
                    const bool sized = checked_mul(h.uniform ? 1 : h.size, std::uint64_t(h.stride) * storage[a].bytes * storage[a].components, expected);
                    if (!sized || !keep[a] || expected > max_inflated_size(h.bytes)) c_.fail(what + ": a compressed array that cannot be sized");
                    unpaged.resize(static_cast<std::size_t>(expected));
                    blosc_decompress(c_.source().path, in, h.bytes, unpaged.data(), unpaged.size(), what);
                    data = unpaged.data();
                } else {
                    data = in;
                }
            }
            if (keep[a]) {
                const Storage& s = storage[a];
                const std::size_t value_bytes = s.bytes * s.components * h.stride;  // small: the stride is bounded
                std::uint64_t stored_bytes = 0;
                if (!checked_mul(h.uniform ? 1 : std::uint64_t(h.size), value_bytes, stored_bytes) || (unpaged.empty() && stored_bytes != h.bytes))
                    c_.fail(what + ": " + std::to_string(h.bytes) + " bytes for " + std::to_string(h.uniform ? 1 : h.size) +
                            " values of " + std::to_string(value_bytes) + " bytes");
                for (std::size_t v = 0, p = 0; v < kLeafVoxels; ++v) {
                    for (; p < leaf.end_offsets[v]; ++p) {
                        const unsigned char* value = data + (h.uniform ? 0 : p * value_bytes);
                        if (a == position_index) {
                            const std::int32_t i = leaf.origin[0] + static_cast<std::int32_t>(v >> 6);
                            const std::int32_t j = leaf.origin[1] + static_cast<std::int32_t>((v >> 3) & 7);
                            const std::int32_t k = leaf.origin[2] + static_cast<std::int32_t>(v & 7);
                            const auto w = transform.apply(i + decode_component(value, s), j + decode_component(value + s.bytes, s),
                                                           k + decode_component(value + 2 * s.bytes, s));
                            for (int c = 0; c < 3; ++c) out.positions[3 * (first_point + p) + c] = static_cast<float>(w[c]);
                        } else {
                            Attribute& attr = out.attributes[attribute_slot[a]];
                            for (std::size_t c = 0; c < std::size_t(attr.components); ++c)
                                attr.values.push_back(static_cast<float>(decode_component(value + c * s.bytes, s)));
                        }
                    }
                }
            }
            first_point += leaf.points();
        }
        if (!pages[a].empty() && page_fill[a] != page_end)
            c_.fail(grid + ": attribute " + quote(descriptor[a].name) + "'s last page is not used up");
    }
    for (const Attribute& attr : out.attributes)
        if (attr.values.size() != total * std::size_t(attr.components))
            c_.fail(grid + ": attribute " + quote(attr.name) + " changes its stride between leaves");
    return out;
}

ParticleData VdbReader::read() {
    const unsigned char* magic = c_.take(8, "the magic");
    if (load_le64(magic) != 0x56444220u) c_.fail("not an OpenVDB file (no ' BDV' magic)");
    version_ = u32("the file version");
    if (version_ < kMinVersion)
        c_.fail("OpenVDB file version " + std::to_string(version_) + " is older than " + std::to_string(kMinVersion) + " (OpenVDB 3), which is not supported");
    u32("the library major version");
    u32("the library minor version");
    const bool offsets = c_.u8("the grid offsets flag") != 0;
    c_.take(36, "the file's UUID");
    skip_metadata("the file's metadata");
    if (!offsets) c_.fail("an OpenVDB stream without grid offsets is not supported (save it as a .vdb file)");
    const std::size_t count_at = c_.pos();
    const std::int32_t grids = i32("the grid count");
    if (grids < 0 || static_cast<std::uint64_t>(grids) > c_.remaining() / 36)
        c_.fail(std::to_string(grids) + " grids at " + c_.where(count_at) + " cannot be in the file");
    std::vector<ParticleData> point_grids;
    std::vector<std::string> other;
    for (std::int32_t g = 0; g < grids; ++g) {
        const std::string name = string("a grid name");
        std::string type = string("a grid type");
        const std::string parent = string("a grid's instance parent");
        const std::size_t offsets_at = c_.pos();
        const std::int64_t grid_pos = i64("the grid's offset"), block_pos = i64("the grid's buffer offset"), end_pos = i64("the grid's end");
        if (grid_pos < static_cast<std::int64_t>(c_.pos()) || block_pos < grid_pos || end_pos < block_pos || end_pos > static_cast<std::int64_t>(c_.size()))
            c_.fail("grid " + quote(name) + " has offsets " + std::to_string(grid_pos) + ", " + std::to_string(block_pos) + ", " + std::to_string(end_pos) +
                    " at " + c_.where(offsets_at) + " that do not lie in order inside the file");
        const std::string half = "_HalfFloat";
        if (type.size() > half.size() && type.compare(type.size() - half.size(), half.size(), half) == 0) type.resize(type.size() - half.size());
        if (type.rfind("Tree_ptdataidx32", 0) == 0 && parent.empty()) {
            if (type != "Tree_ptdataidx32_5_4_3") c_.fail("point grid " + quote(name) + " has the tree layout " + quote(type) + " (5_4_3 is supported)");
            c_.seek(static_cast<std::size_t>(grid_pos));
            point_grids.push_back(read_point_grid(name, static_cast<std::uint64_t>(block_pos)));
            if (c_.pos() > static_cast<std::size_t>(end_pos))  // overlapping grids would be read again
                c_.fail("point grid " + quote(name) + " runs to byte " + std::to_string(c_.pos()) + ", past its end at byte " + std::to_string(end_pos));
        } else {
            other.push_back(name + " (" + type + ")");
        }
        c_.seek(static_cast<std::size_t>(end_pos));
    }
    if (point_grids.empty()) {
        std::string list;
        for (const auto& o : other) list += (list.empty() ? "" : ", ") + o;
        c_.fail("holds no OpenVDB point data grid (only " + (list.empty() ? std::string("no grids") : list) + "); meniscus reads particles");
    }
    ParticleData out = std::move(point_grids[0]);
    for (std::size_t g = 1; g < point_grids.size(); ++g) {  // several point grids: one particle set, shared attributes
        ParticleData& more = point_grids[g];
        out.positions.insert(out.positions.end(), more.positions.begin(), more.positions.end());
        std::vector<Attribute> kept;
        for (Attribute& a : out.attributes)
            for (Attribute& b : more.attributes)
                if (a.name == b.name && a.components == b.components) {
                    a.values.insert(a.values.end(), b.values.begin(), b.values.end());
                    kept.push_back(std::move(a));
                    break;
                }
        out.attributes = std::move(kept);
    }
    return out;
}

}  // namespace

ParticleData read_vdb_points(const Source& source) { return VdbReader(source).read(); }

}  // namespace io_detail
}  // namespace meniscus
