// Houdini JSON geometry (Houdini 12 and later): ASCII .geo (plain JSON) and binary .bgeo (SideFX binary JSON,
// magic 0x7f "NSJb", or 0x7f "bJSN" when written big-endian), plain or gzip-compressed. The classic "BgeoV" layout is
// io_bgeo.cpp.
//
// The file is one JSON value: a flat array of key/value pairs (["fileversion", "19.5.303", "pointcount", 4732, ...]).
// Particles need "pointcount" and "attributes" -> "pointattributes": a list of [definition, body] pairs where the
// definition names the attribute (P is the position) and body["values"] holds the data in one of three layouts:
// "tuples" ([[x, y, z], ...]), "arrays" ([[x0, x1, ...], [y0, ...], ...]) or paged "rawpagedata" (pages of
// "pagesize" elements; within a page, each "packing" group of components stored element by element; a page whose
// group is flagged in "constantpageflags" stores that group's tuple once). Numeric attributes are kept; string and
// index attributes are skipped; everything else in the file (topology, primitives, groups, vertex and detail
// attributes) is parsed only to be skipped, without building values for it.
//
// Binary JSON (UT_JSONDefines.h): one byte per token, lengths as encoded integers (a byte below 0xf1, or 0xf2 / 0xf4 /
// 0xf8 followed by 2 / 4 / 8 bytes), strings as length + bytes, "token definitions" that give ids to strings,
// and uniform arrays (token 0x40, element type, length, raw data) for numeric runs, which are kept as views into the
// file instead of being copied.
//
// Not supported: the Blosc-compressed .sc variants (no Blosc decoder here) and the classic ASCII "PGEOMETRY" .geo.
// No Houdini-written JSON sample was available to the tests: the layouts follow the published binary JSON
// definitions and the geometry structure as other open readers decode it, and are tested on files written to them.
#include <algorithm>
#include <cmath>
#include <map>

#include "io/io_util.h"

namespace meniscus {
namespace io_detail {
namespace {

constexpr int kMaxDepth = 64;

// One JSON value. Numeric arrays are packed: ASCII ones into `numbers`, binary uniform arrays as a view of the file.
struct JValue {
    // numbers: a packed array of plain numbers; matrix: packed equal-length numeric rows (tuples), `width` each.
    enum class Kind : std::uint8_t { null, boolean, number, string, array, map, numbers, matrix, uniform, bits } kind = Kind::null;
    double number = 0.0;
    std::string text;                                      // string
    std::vector<JValue> items;                             // array (and map values, with keys in `keys`)
    std::vector<std::string> keys;                         // map keys
    std::vector<double> numbers;                           // packed numbers or matrix rows
    std::uint64_t width = 0;                               // matrix row length
    const unsigned char* data = nullptr;                   // uniform binary array
    ScalarType type = ScalarType::f32;
    bool big_endian = false;
    std::uint64_t count = 0;

    bool is_sequence() const { return kind == Kind::array || kind == Kind::numbers || kind == Kind::uniform || kind == Kind::bits; }
    // (a matrix is a sequence of rows, not of numbers: see rows())
    std::uint64_t size() const {
        switch (kind) {
            case Kind::array: return items.size();
            case Kind::numbers: return numbers.size();
            case Kind::matrix: return width ? numbers.size() / width : 0;
            case Kind::uniform:
            case Kind::bits: return count;
            default: return 0;
        }
    }
    bool is_row() const { return (kind == Kind::numbers || kind == Kind::uniform) && size() >= 1 && size() <= 64; }
    // Element i of a numeric sequence as a double (NaN when it is not a number).
    double at(std::uint64_t i) const {
        if (kind == Kind::numbers) return numbers[static_cast<std::size_t>(i)];
        if (kind == Kind::uniform) return decode_scalar(data + i * scalar_size(type), type, big_endian);
        if (kind == Kind::bits) {  // packed booleans: bit i % 32 of 32-bit word i / 32
            const unsigned char* w = data + 4 * (i / 32);
            return ((big_endian ? load_be32(w) : load_le32(w)) >> (i % 32)) & 1u;
        }
        const JValue& v = items[static_cast<std::size_t>(i)];
        return v.kind == Kind::number ? v.number : v.kind == Kind::boolean ? v.number : std::nan("");
    }
    // A 2-D numeric table: a packed matrix, or an array whose items are numeric sequences. rows() is 0 when the value
    // is neither; row_size(i) is the length of row i; cell(i, j) an element.
    std::uint64_t rows() const {
        if (kind == Kind::matrix) return size();
        if (kind != Kind::array) return 0;
        for (const auto& v : items)
            if (!v.is_sequence() || !v.all_numeric()) return 0;
        return items.size();
    }
    std::uint64_t row_size(std::uint64_t i) const { return kind == Kind::matrix ? width : items[static_cast<std::size_t>(i)].size(); }
    double cell(std::uint64_t i, std::uint64_t j) const {
        return kind == Kind::matrix ? numbers[static_cast<std::size_t>(i * width + j)] : items[static_cast<std::size_t>(i)].at(j);
    }

    bool all_numeric() const {
        if (kind == Kind::numbers || kind == Kind::uniform || kind == Kind::bits) return true;
        if (kind != Kind::array) return false;
        for (const auto& v : items)
            if (v.kind != Kind::number && v.kind != Kind::boolean) return false;
        return true;
    }
};

// Houdini writes dictionaries as flat [key, value, key, value] arrays or as JSON objects; both look up the same.
const JValue* lookup(const JValue& v, std::string_view key) {
    if (v.kind == JValue::Kind::map) {
        for (std::size_t i = 0; i < v.keys.size(); ++i)
            if (v.keys[i] == key) return &v.items[i];
        return nullptr;
    }
    if (v.kind != JValue::Kind::array) return nullptr;
    for (std::size_t i = 0; i + 1 < v.items.size(); i += 2)
        if (v.items[i].kind == JValue::Kind::string && v.items[i].text == key) return &v.items[i + 1];
    return nullptr;
}

// Keys whose values the reader needs at each level; everything else is skipped while parsing.
bool wanted_at_root(std::string_view key) { return key == "pointcount" || key == "attributes" || key == "fileversion"; }
bool wanted_in_attributes(std::string_view key) { return key == "pointattributes"; }

// How deep in the document a value sits, and whether it is kept: only the point count and the point attributes are.
enum class JsonLevel { root, attributes, kept, skip };

// The level of a child value. keyed: the child is a value with a key (a map entry, or an array item following its
// key string, as Houdini writes maps); it is kept when the key is wanted at this level, and "attributes" is read
// at the attributes level. Shared by the ASCII and the binary parser.
JsonLevel child_level(JsonLevel level, bool keep, bool keyed, const std::string& key) {
    if (!keep) return JsonLevel::skip;
    if (level == JsonLevel::kept || !keyed) return level;
    if (level == JsonLevel::root)
        return !wanted_at_root(key) ? JsonLevel::skip : key == "attributes" ? JsonLevel::attributes : JsonLevel::kept;
    return wanted_in_attributes(key) ? JsonLevel::kept : JsonLevel::skip;
}

// Memory: values are built only for the point attributes, numbers are packed (8 bytes each), and what is built is
// charged against a budget relative to the file, so that a file of nested empty arrays or one-number tuples cannot
// turn into gigabytes of nodes.
class Budget {
public:
    Budget(const Cursor& c, std::size_t file_size) : c_(c), left_(16 * std::uint64_t(file_size) + (std::uint64_t(64) << 20)) {}
    void take(std::uint64_t bytes) {
        if (bytes > left_)
            c_.fail("the JSON structure needs more memory than a geometry file of this size justifies (corrupt, or not "
                    "particle data)");
        left_ -= bytes;
    }

private:
    const Cursor& c_;
    std::uint64_t left_;
};

// Collects the elements of a kept array: runs of plain numbers and of equal-length numeric rows (tuples such as
// [x, y, z]) go into one packed vector instead of one node each; anything else turns the array into plain nodes.
class ArrayBuilder {
public:
    ArrayBuilder(JValue& out, Budget& budget) : out_(out), budget_(budget) {}

    void add(JValue&& item) {
        const bool scalar = item.kind == JValue::Kind::number || item.kind == JValue::Kind::boolean;
        if (mode_ == Mode::empty) mode_ = scalar ? Mode::scalars : item.is_row() ? Mode::rows : Mode::nodes;
        if (mode_ == Mode::scalars && scalar) {
            budget_.take(sizeof(double));
            out_.numbers.push_back(item.number);
            return;
        }
        if (mode_ == Mode::rows && item.is_row() && (out_.width == 0 || item.size() == out_.width)) {
            out_.width = item.size();
            budget_.take(sizeof(double) * out_.width);
            for (std::uint64_t j = 0; j < out_.width; ++j) out_.numbers.push_back(item.at(j));
            return;
        }
        unpack();
        budget_.take(sizeof(JValue));
        out_.items.push_back(std::move(item));
    }

    // A scalar parsed straight from text (no node made for it).
    void add_number(double v) {
        if (mode_ == Mode::empty) mode_ = Mode::scalars;
        if (mode_ == Mode::scalars) {
            budget_.take(sizeof(double));
            out_.numbers.push_back(v);
            return;
        }
        JValue n;
        n.kind = JValue::Kind::number;
        n.number = v;
        add(std::move(n));
    }

    void finish() {
        if (mode_ == Mode::scalars) out_.kind = JValue::Kind::numbers;
        if (mode_ == Mode::rows) out_.kind = JValue::Kind::matrix;
    }

private:
    JValue& out_;
    Budget& budget_;
    enum class Mode { empty, scalars, rows, nodes } mode_ = Mode::empty;

    // Mixed content after a packed run: the run goes back to nodes (rare; real files are uniform).
    void unpack() {
        if (mode_ == Mode::nodes) return;
        std::vector<double> packed;
        packed.swap(out_.numbers);
        const std::uint64_t width = mode_ == Mode::rows ? out_.width : 1;
        for (std::size_t i = 0; i + width <= packed.size(); i += static_cast<std::size_t>(width)) {
            budget_.take(sizeof(JValue));
            JValue v;
            if (mode_ == Mode::rows) {
                v.kind = JValue::Kind::numbers;
                v.numbers.assign(packed.begin() + static_cast<std::ptrdiff_t>(i), packed.begin() + static_cast<std::ptrdiff_t>(i + width));
            } else {
                v.kind = JValue::Kind::number;
                v.number = packed[i];
            }
            out_.items.push_back(std::move(v));
        }
        out_.width = 0;
        mode_ = Mode::nodes;
    }
};

// ---- ASCII JSON ----------------------------------------------------------------------------------------------

class TextJson {
public:
    explicit TextJson(const Source& s) : c_(s), budget_(c_, s.size) {}

    JValue parse_document() {
        JValue root;
        value(root, 0, Level::root);
        c_.skip_space();
        if (!c_.at_end()) c_.fail("unexpected " + quote(c_.view(c_.pos(), std::min(c_.size(), c_.pos() + 10))) + " after the JSON value at " + c_.where());
        return root;
    }

    const Cursor& cursor() const { return c_; }

private:
    Cursor c_;
    Budget budget_;
    using Level = JsonLevel;

    [[noreturn]] void fail(const std::string& what) { c_.fail("bad JSON at " + c_.where() + ": " + what); }

    int peek() {
        c_.skip_space();
        return c_.at_end() ? -1 : *c_.here();
    }

    void expect(char ch) {
        if (peek() != ch) fail(std::string("expected '") + ch + "'" + (c_.at_end() ? " (truncated?)" : ""));
        c_.take(1, "JSON");
    }

    std::string string_value(bool keep) {
        expect('"');
        std::string out;
        while (true) {
            if (c_.at_end()) fail("a string is not closed (truncated?)");
            char ch = static_cast<char>(c_.u8("string"));
            if (ch == '"') return out;
            if (ch == '\\') {
                if (c_.at_end()) fail("a string is not closed (truncated?)");
                char e = static_cast<char>(c_.u8("escape"));
                switch (e) {
                    case 'n': ch = '\n'; break;
                    case 't': ch = '\t'; break;
                    case 'r': ch = '\r'; break;
                    case 'b': ch = '\b'; break;
                    case 'f': ch = '\f'; break;
                    case 'u': c_.take(4, "\\u escape"); ch = '?'; break;  // names are ASCII; keep the length honest
                    default: ch = e;
                }
            }
            if (keep) out += ch;
        }
    }

    double number_value() {
        std::size_t start = c_.pos();
        while (!c_.at_end()) {
            char ch = static_cast<char>(*c_.here());
            if (!((ch >= '0' && ch <= '9') || ch == '-' || ch == '+' || ch == '.' || ch == 'e' || ch == 'E')) break;
            c_.take(1, "number");
        }
        double v = 0;
        std::string_view token = c_.view(start, c_.pos());
        if (!parse_double(token, v)) {
            c_.seek(start);
            fail("bad number " + quote(token));
        }
        return v;
    }

    bool word(std::string_view w) {
        if (c_.remaining() < w.size() || c_.view(c_.pos(), c_.pos() + w.size()) != w) return false;
        c_.take(w.size(), "JSON");
        return true;
    }

    // Level decides what is kept: the root's wanted keys, "pointattributes" in "attributes", all of what is kept.
    void value(JValue& out, int depth, Level level) {
        if (depth > kMaxDepth) fail("nested more than " + std::to_string(kMaxDepth) + " levels deep");
        const bool keep = level != Level::skip;
        int ch = peek();
        if (ch < 0) fail("a value is missing (truncated?)");
        if (ch == '"') {
            out.kind = JValue::Kind::string;
            out.text = string_value(keep);
            if (keep) budget_.take(out.text.size());
        } else if (ch == '[' || ch == '{') {
            const bool is_map = ch == '{';
            c_.take(1, "JSON");
            out.kind = is_map ? JValue::Kind::map : JValue::Kind::array;
            ArrayBuilder builder(out, budget_);
            bool first = true;
            std::string pending_key;  // flat [key, value] arrays: the key just read
            bool after_key = false;
            while (true) {
                if (peek() == (is_map ? '}' : ']')) {
                    c_.take(1, "JSON");
                    break;
                }
                if (!first) expect(',');
                first = false;
                std::string key;
                if (is_map) {
                    key = string_value(true);
                    expect(':');
                }
                const int next = peek();
                if (!is_map && (next == '-' || (next >= '0' && next <= '9'))) {  // the common case: no node at all
                    double v = number_value();
                    if (keep) builder.add_number(v);
                    after_key = false;
                    continue;
                }
                const Level child = child_level(level, keep, is_map || after_key, is_map ? key : pending_key);
                JValue item;
                value(item, depth + 1, child);
                after_key = !is_map && !after_key && item.kind == JValue::Kind::string;
                if (after_key) pending_key = item.text;
                if (!keep) continue;
                if (is_map) {
                    budget_.take(sizeof(JValue) + key.size());
                    out.keys.push_back(std::move(key));
                    out.items.push_back(std::move(item));
                } else {
                    builder.add(std::move(item));
                }
            }
            if (!is_map) builder.finish();
        } else if (ch == 't' && word("true")) {
            out.kind = JValue::Kind::boolean;
            out.number = 1;
        } else if (ch == 'f' && word("false")) {
            out.kind = JValue::Kind::boolean;
        } else if (ch == 'n' && word("null")) {
            out.kind = JValue::Kind::null;
        } else if (ch == '-' || (ch >= '0' && ch <= '9')) {
            out.kind = JValue::Kind::number;
            out.number = number_value();
        } else {
            fail("unexpected character " + quote(std::string(1, static_cast<char>(ch))));
        }
    }
};

// ---- binary JSON ---------------------------------------------------------------------------------------------

enum : unsigned char {
    kNull = 0x00, kMapBegin = 0x7b, kMapEnd = 0x7d, kArrayBegin = 0x5b, kArrayEnd = 0x5d, kBool = 0x10, kInt8 = 0x11,
    kInt16 = 0x12, kInt32 = 0x13, kInt64 = 0x14, kReal16 = 0x18, kReal32 = 0x19, kReal64 = 0x1a, kUInt8 = 0x21,
    kUInt16 = 0x22, kString = 0x27, kFalse = 0x30, kTrue = 0x31, kTokenDef = 0x2b, kTokenRef = 0x26, kTokenUndef = 0x2d,
    kUniformArray = 0x40, kMagic = 0x7f,
};

float half_bits_to_float(std::uint16_t h) {
    const std::uint32_t sign = std::uint32_t(h >> 15) << 31;
    std::uint32_t exponent = (h >> 10) & 31, mantissa = h & 1023;
    if (exponent == 31) return bits_to_float(sign | 0x7f800000u | (mantissa << 13));
    if (exponent == 0) {
        float v = std::ldexp(static_cast<float>(mantissa), -24);
        return sign ? -v : v;
    }
    return bits_to_float(sign | ((exponent + 112) << 23) | (mantissa << 13));
}

class BinaryJson {
public:
    explicit BinaryJson(const Source& s) : c_(s), budget_(c_, s.size) {}

    JValue parse_document() {
        c_.take(1, "binary JSON magic");
        std::uint32_t magic = load_le32(c_.take(4, "binary JSON magic"));
        if (magic == 0x624a534eu)
            big_ = false;
        else if (magic == 0x4e534a62u)
            big_ = true;
        else
            c_.fail("not Houdini binary JSON: bad magic number after 0x7f");
        JValue root;
        value(root, next_token(), 0, Level::root);
        return root;  // trailing bytes (an index some versions append) are ignored
    }

private:
    Cursor c_;
    Budget budget_;
    bool big_ = false;
    std::map<std::uint64_t, std::string> tokens_;
    using Level = JsonLevel;

    std::uint64_t u(std::size_t n, const char* what) {
        const unsigned char* p = c_.take(n, what);
        switch (n) {
            case 1: return p[0];
            case 2: return big_ ? load_be16(p) : load_le16(p);
            case 4: return big_ ? load_be32(p) : load_le32(p);
            default: return big_ ? load_be64(p) : load_le64(p);
        }
    }

    std::uint64_t length(const char* what) {
        std::size_t pos = c_.pos();
        unsigned lead = c_.u8(what);
        if (lead < 0xf1) return lead;
        if (lead == 0xf2) return u(2, what);
        if (lead == 0xf4) return u(4, what);
        if (lead == 0xf8) return u(8, what);
        c_.fail("bad binary JSON length prefix " + std::to_string(lead) + " at " + c_.where(pos));
    }

    std::string string_data(bool keep) {
        std::uint64_t n = length("string length");
        const unsigned char* p = c_.take(n, "string");
        return keep ? std::string(reinterpret_cast<const char*>(p), static_cast<std::size_t>(n)) : std::string();
    }

    // The next token that is not a token (un)definition.
    unsigned next_token() {
        while (true) {
            unsigned token = c_.u8("binary JSON token");
            if (token == kTokenDef) {
                std::uint64_t id = length("token id");
                std::string s = string_data(true);
                if (tokens_.size() > c_.size()) c_.fail("too many string tokens");
                tokens_[id] = std::move(s);
                continue;
            }
            if (token == kTokenUndef) {
                tokens_.erase(length("token id"));
                continue;
            }
            return token;
        }
    }

    std::string token_string(std::size_t pos) {
        std::uint64_t id = length("token id");
        auto it = tokens_.find(id);
        if (it == tokens_.end()) c_.fail("reference to undefined string token " + std::to_string(id) + " at " + c_.where(pos));
        return it->second;
    }

    void uniform(JValue& out, bool keep) {
        std::size_t pos = c_.pos();
        unsigned type = c_.u8("uniform array type");
        std::uint64_t n = length("uniform array length");
        ScalarType t;
        switch (type) {
            case kInt8: t = ScalarType::i8; break;
            case kInt16: t = ScalarType::i16; break;
            case kInt32: t = ScalarType::i32; break;
            case kInt64: t = ScalarType::i64; break;
            case kUInt8: t = ScalarType::u8; break;
            case kUInt16: t = ScalarType::u16; break;
            case kReal32: t = ScalarType::f32; break;
            case kReal64: t = ScalarType::f64; break;
            case kReal16: {
                // Rare: converted to a packed array of doubles (the element count is checked against the bytes first).
                std::uint64_t bytes = 0;
                if (!checked_mul(n, 2, bytes)) c_.fail("uniform array length " + std::to_string(n) + " is impossibly large");
                const unsigned char* p = c_.take(bytes, "uniform float16 array");
                if (keep) {
                    budget_.take(bytes * 4);  // 2 bytes become 8
                    out.kind = JValue::Kind::numbers;
                    out.numbers.resize(static_cast<std::size_t>(n));
                    for (std::size_t i = 0; i < out.numbers.size(); ++i)
                        out.numbers[i] = half_bits_to_float(static_cast<std::uint16_t>(big_ ? load_be16(p + 2 * i) : load_le16(p + 2 * i)));
                }
                return;
            }
            case kBool: {
                std::uint64_t words = n / 32 + (n % 32 != 0), bytes = 0;
                if (!checked_mul(words, 4, bytes)) c_.fail("uniform array length " + std::to_string(n) + " is impossibly large");
                out.data = c_.take(bytes, "uniform bool array");
                out.kind = JValue::Kind::bits;
                out.big_endian = big_;
                out.count = n;
                return;
            }
            case kString:
            case kTokenRef:
                // Strings have no float meaning: skipped (each still needs at least one byte, so n is bounded).
                if (n > c_.remaining()) c_.fail("uniform string array of " + std::to_string(n) + " strings cannot fit in the bytes left");
                for (std::uint64_t i = 0; i < n; ++i) {
                    if (type == kString) string_data(false);
                    else length("token id");
                }
                out.kind = JValue::Kind::array;
                return;
            default:
                c_.fail("unknown uniform array element type " + std::to_string(type) + " at " + c_.where(pos));
        }
        std::uint64_t bytes = 0;
        if (!checked_mul(n, scalar_size(t), bytes)) c_.fail("uniform array length " + std::to_string(n) + " is impossibly large");
        const unsigned char* p = c_.take(bytes, "uniform array of " + std::to_string(n) + " values");
        out.kind = JValue::Kind::uniform;
        out.data = p;
        out.type = t;
        out.big_endian = big_;
        out.count = n;
    }

    void value(JValue& out, unsigned token, int depth, Level level) {
        if (depth > kMaxDepth) c_.fail("binary JSON nested more than " + std::to_string(kMaxDepth) + " levels deep at " + c_.where());
        const bool keep = level != Level::skip;
        std::size_t pos = c_.pos() - 1;
        auto number = [&](double v) {
            out.kind = JValue::Kind::number;
            out.number = v;
        };
        switch (token) {
            case kNull: return;
            case kFalse: out.kind = JValue::Kind::boolean; return;
            case kTrue: out.kind = JValue::Kind::boolean; out.number = 1; return;
            case kBool: out.kind = JValue::Kind::boolean; out.number = c_.u8("bool") ? 1 : 0; return;
            case kInt8: number(static_cast<std::int8_t>(u(1, "int8"))); return;
            case kInt16: number(static_cast<std::int16_t>(u(2, "int16"))); return;
            case kInt32: number(static_cast<std::int32_t>(u(4, "int32"))); return;
            case kInt64: number(static_cast<double>(static_cast<std::int64_t>(u(8, "int64")))); return;
            case kUInt8: number(static_cast<double>(u(1, "uint8"))); return;
            case kUInt16: number(static_cast<double>(u(2, "uint16"))); return;
            case kReal16: number(half_bits_to_float(static_cast<std::uint16_t>(u(2, "real16")))); return;
            case kReal32: number(bits_to_float(static_cast<std::uint32_t>(u(4, "real32")))); return;
            case kReal64: number(bits_to_double(u(8, "real64"))); return;
            case kString:
                out.kind = JValue::Kind::string;
                out.text = string_data(keep);
                if (keep) budget_.take(out.text.size());
                return;
            case kTokenRef: out.kind = JValue::Kind::string; out.text = token_string(pos); return;
            case kUniformArray: uniform(out, keep); return;
            case kArrayBegin:
            case kMapBegin: {
                const bool is_map = token == kMapBegin;
                out.kind = is_map ? JValue::Kind::map : JValue::Kind::array;
                ArrayBuilder builder(out, budget_);
                std::string pending_key;
                bool after_key = false;
                while (true) {
                    unsigned t = next_token();
                    if (t == (is_map ? kMapEnd : kArrayEnd)) break;
                    std::string key;
                    if (is_map) {
                        if (t == kString) key = string_data(true);
                        else if (t == kTokenRef) key = token_string(c_.pos() - 1);
                        else c_.fail("a binary JSON map key at " + c_.where(c_.pos() - 1) + " is not a string");
                        t = next_token();
                    }
                    const Level child = child_level(level, keep, is_map || after_key, is_map ? key : pending_key);
                    JValue item;
                    value(item, t, depth + 1, child);
                    after_key = !is_map && !after_key && item.kind == JValue::Kind::string;
                    if (after_key) pending_key = item.text;
                    if (!keep) continue;
                    if (is_map) {
                        budget_.take(sizeof(JValue) + key.size());
                        out.keys.push_back(std::move(key));
                        out.items.push_back(std::move(item));
                    } else {
                        builder.add(std::move(item));
                    }
                }
                if (!is_map) builder.finish();
                    return;
            }
            default:
                c_.fail("unknown binary JSON token " + std::to_string(token) + " at " + c_.where(pos));
        }
    }
};

// ---- geometry ------------------------------------------------------------------------------------------------

class Geometry {
public:
    Geometry(const Cursor& c, const JValue& root, std::size_t file_size) : c_(c), root_(root), file_size_(file_size) {}

    ParticleData read() {
        const JValue* count = lookup(root_, "pointcount");
        if (!count || count->kind != JValue::Kind::number || !(count->number >= 0) || count->number > 1e15 ||
            count->number != std::floor(count->number))
            c_.fail("Houdini geometry without a valid \"pointcount\"");
        n_ = static_cast<std::uint64_t>(count->number);
        const JValue* attributes = lookup(root_, "attributes");
        const JValue* points = attributes ? lookup(*attributes, "pointattributes") : nullptr;
        ParticleData out;
        bool have_p = false;
        if (points && points->kind == JValue::Kind::array) {
            for (const JValue& entry : points->items) {
                if (entry.kind != JValue::Kind::array || entry.items.size() != 2) c_.fail("a point attribute is not a [definition, values] pair");
                const JValue* name = lookup(entry.items[0], "name");
                const JValue* type = lookup(entry.items[0], "type");
                if (!name || name->kind != JValue::Kind::string) c_.fail("a point attribute has no name");
                if (!type || type->kind != JValue::Kind::string || type->text != "numeric") continue;  // strings, indices
                int components = 0;
                std::vector<float> values = decode(name->text, entry.items[1], components);
                if (name->text == "P") {
                    if (components < 3) c_.fail("the point attribute P has " + std::to_string(components) + " components, 3 needed");
                    out.positions.resize(static_cast<std::size_t>(3 * n_));
                    for (std::size_t i = 0; i < n_; ++i)
                        for (int k = 0; k < 3; ++k) out.positions[3 * i + k] = values[i * static_cast<std::size_t>(components) + k];
                    have_p = true;
                    continue;
                }
                Attribute a;
                a.name = name->text;
                a.components = components;
                a.integral = integer_storage(entry.items[1]);
                a.values = std::move(values);
                out.attributes.push_back(std::move(a));
            }
        }
        if (!have_p && n_ > 0) c_.fail("Houdini geometry with " + std::to_string(n_) + " points has no numeric point attribute P");
        return out;
    }

private:
    Cursor c_;
    const JValue& root_;
    std::size_t file_size_;
    std::uint64_t n_ = 0;

    static int small_int(const JValue* v) {
        if (!v || v->kind != JValue::Kind::number || !(v->number >= 1) || v->number > 65536 || v->number != std::floor(v->number)) return 0;
        return static_cast<int>(v->number);
    }

    // Whether a point attribute's values are stored as integers ("storage": "int32", "uint8", ...).
    static bool integer_storage(const JValue& body) {
        const JValue* values = lookup(body, "values");
        const JValue* storage = values ? lookup(*values, "storage") : nullptr;
        return storage && storage->kind == JValue::Kind::string &&
               (storage->text.rfind("int", 0) == 0 || storage->text.rfind("uint", 0) == 0);
    }

    std::vector<float> decode(const std::string& name, const JValue& body, int& components) {
        const std::string what = "point attribute " + quote(name);
        const JValue* values = lookup(body, "values");
        if (!values) c_.fail(what + " has no \"values\"");
        components = small_int(lookup(*values, "size"));
        if (!components) components = small_int(lookup(body, "size"));
        if (!components) c_.fail(what + " has no valid tuple size");
        const std::size_t k = static_cast<std::size_t>(components);
        std::uint64_t total = 0;
        if (!checked_mul(n_, k, total)) c_.fail(what + ": pointcount times tuple size is impossibly large");
        std::vector<float> out;
        auto allocate = [&](std::uint64_t available) {
            // Every value must come from the file: refuse before allocating what the data cannot fill.
            if (total > available)
                c_.fail(what + " holds " + std::to_string(available) + " values but " + std::to_string(n_) + " points of " +
                        std::to_string(k) + " components need " + std::to_string(total));
            out.resize(static_cast<std::size_t>(total));
        };
        if (const JValue* tuples = lookup(*values, "tuples")) {
            if (tuples->all_numeric() && tuples->kind != JValue::Kind::array) {  // a flat numeric array: 1 component
                if (k != 1 || tuples->size() != n_)
                    c_.fail(what + " has " + std::to_string(tuples->size()) + " values as tuples for " + std::to_string(n_) +
                            " points of " + std::to_string(k) + " components");
                allocate(n_);
                for (std::size_t i = 0; i < n_; ++i) out[i] = static_cast<float>(tuples->at(i));
                return out;
            }
            const std::uint64_t rows = tuples->rows();
            if (rows != n_)
                c_.fail(what + " has " + std::to_string(rows) + " numeric tuples for " + std::to_string(n_) + " points");
            // Every tuple is checked before the output is allocated: the tuple size alone must not decide it.
            for (std::uint64_t i = 0; i < n_; ++i)
                if (tuples->row_size(i) < k)
                    c_.fail(what + ": tuple " + std::to_string(i) + " does not hold " + std::to_string(k) + " numbers");
            allocate(total);
            for (std::uint64_t i = 0; i < n_; ++i)
                for (std::size_t j = 0; j < k; ++j) out[static_cast<std::size_t>(i * k + j)] = static_cast<float>(tuples->cell(i, j));
            return out;
        }
        if (const JValue* arrays = lookup(*values, "arrays")) {
            if (arrays->rows() != k) c_.fail(what + ": \"arrays\" does not hold one numeric array per component");
            for (std::uint64_t j = 0; j < k; ++j)
                if (arrays->row_size(j) != n_)
                    c_.fail(what + ": a component array does not hold " + std::to_string(n_) + " numbers");
            allocate(total);
            for (std::size_t j = 0; j < k; ++j)
                for (std::uint64_t i = 0; i < n_; ++i) out[static_cast<std::size_t>(i * k + j)] = static_cast<float>(arrays->cell(j, i));
            return out;
        }
        if (const JValue* raw = lookup(*values, "rawpagedata")) return paged(what, *values, *raw, k, out, allocate);
        c_.fail(what + ": unsupported value layout (expected tuples, arrays or rawpagedata)");
    }

    template <class Allocate>
    std::vector<float> paged(const std::string& what, const JValue& values, const JValue& raw, std::size_t k,
                             std::vector<float>& out, Allocate allocate) {
        if (!raw.all_numeric()) c_.fail(what + ": rawpagedata is not numeric");
        const JValue* page_value = lookup(values, "pagesize");
        std::uint64_t page = n_ ? n_ : 1;
        if (page_value) {
            if (page_value->kind != JValue::Kind::number || !(page_value->number >= 1) || page_value->number > 1e9)
                c_.fail(what + ": bad pagesize");
            page = static_cast<std::uint64_t>(page_value->number);
        }
        std::vector<std::size_t> packing;
        if (const JValue* p = lookup(values, "packing")) {
            if (!p->all_numeric() || p->size() == 0 || p->size() > k) c_.fail(what + ": bad packing");
            std::size_t sum = 0;
            for (std::uint64_t i = 0; i < p->size(); ++i) {
                double g = p->at(i);
                if (!(g >= 1) || g > static_cast<double>(k)) c_.fail(what + ": bad packing");
                packing.push_back(static_cast<std::size_t>(g));
                sum += packing.back();
            }
            if (sum != k) c_.fail(what + ": packing adds up to " + std::to_string(sum) + ", not the tuple size " + std::to_string(k));
        } else {
            packing.push_back(k);
        }
        const std::uint64_t pages = n_ / page + (n_ % page != 0);
        const std::uint64_t total = n_ * k;  // checked against overflow by decode()
        if (total > 0 && raw.size() == 0) c_.fail(what + ": rawpagedata is empty");
        // Constant-page flags: one list per packing group, one flag per page (an empty list: no constant pages).
        std::vector<std::uint64_t> constant_rows;  // per group: its row in the flags table, or UINT64_MAX
        const JValue* flags = lookup(values, "constantpageflags");
        if (flags) {
            bool empty_array = flags->kind == JValue::Kind::array && flags->items.size() == packing.size();
            for (std::size_t g = 0; empty_array && g < packing.size(); ++g)
                empty_array = flags->items[g].is_sequence() && flags->items[g].size() == 0;
            if (empty_array) {
                flags = nullptr;
            } else if (flags->rows() != packing.size()) {
                c_.fail(what + ": constantpageflags does not have one list per packing group");
            }
        }
        auto is_constant = [&](std::size_t g, std::uint64_t p) { return flags && flags->row_size(g) > 0 && flags->cell(g, p) != 0; };
        if (flags)
            for (std::size_t g = 0; g < packing.size(); ++g)
                if (flags->row_size(g) != 0 && flags->row_size(g) != pages)
                    c_.fail(what + ": constantpageflags has " + std::to_string(flags->row_size(g)) + " flags for " +
                            std::to_string(pages) + " pages");
        // How many values the layout needs, checked against what rawpagedata holds before anything is allocated.
        // Without constant pages that is simply every value; with them, the loop runs once per flag, and the flags
        // are in the file.
        const bool any_constant = flags != nullptr;
        std::uint64_t needed = total;
        if (any_constant) {
            needed = 0;
            for (std::uint64_t p = 0; p < pages; ++p) {
                const std::uint64_t in_page = std::min(page, n_ - p * page);
                for (std::size_t g = 0; g < packing.size(); ++g) needed += (is_constant(g, p) ? 1 : in_page) * packing[g];
            }
        }
        if (needed != raw.size())
            c_.fail(what + ": rawpagedata holds " + std::to_string(raw.size()) + " values, the page layout needs " + std::to_string(needed));
        // Constant pages expand: cap the result like decompressed data, relative to the file.
        if (any_constant && total > max_inflated_size(file_size_) / 4)
            c_.fail(what + ": constant pages expand to " + std::to_string(total) + " values, beyond what a file of " +
                    std::to_string(file_size_) + " bytes can describe; refusing a corrupt file");
        allocate(any_constant ? total : raw.size());
        std::uint64_t src = 0;
        for (std::uint64_t p = 0; p < pages; ++p) {
            const std::uint64_t first = p * page, in_page = std::min(page, n_ - first);
            std::size_t offset = 0;
            for (std::size_t g = 0; g < packing.size(); ++g) {
                const bool constant = is_constant(g, p);
                for (std::uint64_t e = 0; e < in_page; ++e) {
                    const std::uint64_t from = constant ? src : src + e * packing[g];
                    for (std::size_t j = 0; j < packing[g]; ++j)
                        out[static_cast<std::size_t>((first + e) * k + offset + j)] = static_cast<float>(raw.at(from + j));
                }
                src += (constant ? 1 : in_page) * packing[g];
                offset += packing[g];
            }
        }
        return std::move(out);
    }
};

}  // namespace

ParticleData read_houdini_json_particles(const Source& source) {
    if (source.size >= 1 && source.data[0] == kMagic) {
        BinaryJson parser(source);
        JValue root = parser.parse_document();
        return Geometry(Cursor(source), root, source.size).read();
    }
    TextJson parser(source);
    JValue root = parser.parse_document();
    return Geometry(parser.cursor(), root, source.size).read();
}

}  // namespace io_detail
}  // namespace meniscus
