// SideFX binary JSON (UT_JSONDefines.h): one byte per token, lengths as encoded integers (a byte below 0xf1, or
// 0xf2 / 0xf4 / 0xf8 followed by 2 / 4 / 8 bytes), strings as length + bytes, "token definitions" that give ids to
// strings, and uniform arrays (token 0x40, element type, length, raw data) for numeric runs, which are kept as views
// into the file instead of being copied.
#include <map>

#include "io/parsers/half_float.h"
#include "io/parsers/json.h"

namespace meniscus {
namespace io_detail {
namespace {

enum : unsigned char {
    kNull = 0x00, kMapBegin = 0x7b, kMapEnd = 0x7d, kArrayBegin = 0x5b, kArrayEnd = 0x5d, kBool = 0x10, kInt8 = 0x11,
    kInt16 = 0x12, kInt32 = 0x13, kInt64 = 0x14, kReal16 = 0x18, kReal32 = 0x19, kReal64 = 0x1a, kUInt8 = 0x21,
    kUInt16 = 0x22, kString = 0x27, kFalse = 0x30, kTrue = 0x31, kTokenDef = 0x2b, kTokenRef = 0x26, kTokenUndef = 0x2d,
    kUniformArray = 0x40,
};

class BinaryJsonParser {
public:
    explicit BinaryJsonParser(const Source& s) : c_(s), budget_(c_, s.size) {}

    JsonValue parse_document(const JsonSelection& selection) {
        c_.take(1, "binary JSON magic");
        std::uint32_t magic = load_le32(c_.take(4, "binary JSON magic"));
        if (magic == 0x624a534eu)
            big_ = false;
        else if (magic == 0x4e534a62u)
            big_ = true;
        else
            c_.fail("not Houdini binary JSON: bad magic number after 0x7f");
        JsonValue root;
        value(root, next_token(), 0, &selection);
        return root;
    }

private:
    Cursor c_;
    JsonBudget budget_;
    bool big_ = false;
    std::map<std::uint64_t, std::string> tokens_;  // string token definitions by id

    // An unsigned integer of n bytes in the file's byte order.
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

    // The byte count of n elements of `size` bytes, refused when it overflows.
    std::uint64_t uniform_bytes(std::uint64_t n, std::uint64_t size) {
        std::uint64_t bytes = 0;
        if (!checked_mul(n, size, bytes)) c_.fail("uniform array length " + std::to_string(n) + " is impossibly large");
        return bytes;
    }

    void uniform(JsonValue& out, bool keep) {
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
            case kReal16: return uniform_half(out, n, keep);
            case kBool: return uniform_bits(out, n);
            case kString:
            case kTokenRef: return skip_uniform_strings(out, n, type);
            default: c_.fail("unknown uniform array element type " + std::to_string(type) + " at " + c_.where(pos));
        }
        const unsigned char* p = c_.take(uniform_bytes(n, scalar_size(t)), "uniform array of " + std::to_string(n) + " values");
        out.kind = JsonValue::Kind::uniform;
        out.data = p;
        out.type = t;
        out.big_endian = big_;
        out.count = n;
    }

    // Rare: converted to a packed array of doubles (the element count is checked against the bytes first).
    void uniform_half(JsonValue& out, std::uint64_t n, bool keep) {
        const std::uint64_t bytes = uniform_bytes(n, 2);
        const unsigned char* p = c_.take(bytes, "uniform float16 array");
        if (!keep) return;
        budget_.take(bytes * 4);  // 2 bytes become 8
        out.kind = JsonValue::Kind::numbers;
        out.numbers.resize(static_cast<std::size_t>(n));
        for (std::size_t i = 0; i < out.numbers.size(); ++i)
            out.numbers[i] = half_to_float(static_cast<std::uint16_t>(big_ ? load_be16(p + 2 * i) : load_le16(p + 2 * i)));
    }

    // Booleans packed 32 to a word.
    void uniform_bits(JsonValue& out, std::uint64_t n) {
        out.data = c_.take(uniform_bytes(n / 32 + (n % 32 != 0), 4), "uniform bool array");
        out.kind = JsonValue::Kind::bits;
        out.big_endian = big_;
        out.count = n;
    }

    // Strings have no float meaning: skipped (each still needs at least one byte, so n is bounded).
    void skip_uniform_strings(JsonValue& out, std::uint64_t n, unsigned type) {
        if (n > c_.remaining()) c_.fail("uniform string array of " + std::to_string(n) + " strings cannot fit in the bytes left");
        for (std::uint64_t i = 0; i < n; ++i) {
            if (type == kString)
                string_data(false);
            else
                length("token id");
        }
        out.kind = JsonValue::Kind::array;
    }

    void value(JsonValue& out, unsigned token, int depth, const JsonSelection* selection) {
        if (depth > kMaxJsonDepth)
            c_.fail("binary JSON nested more than " + std::to_string(kMaxJsonDepth) + " levels deep at " + c_.where());
        const bool keep = selection != nullptr;
        const std::size_t pos = c_.pos() - 1;
        auto number = [&](double v) {
            out.kind = JsonValue::Kind::number;
            out.number = v;
        };
        switch (token) {
            case kNull: return;
            case kFalse: out.kind = JsonValue::Kind::boolean; return;
            case kTrue: out.kind = JsonValue::Kind::boolean; out.number = 1; return;
            case kBool: out.kind = JsonValue::Kind::boolean; out.number = c_.u8("bool") ? 1 : 0; return;
            case kInt8: return number(static_cast<std::int8_t>(u(1, "int8")));
            case kInt16: return number(static_cast<std::int16_t>(u(2, "int16")));
            case kInt32: return number(static_cast<std::int32_t>(u(4, "int32")));
            case kInt64: return number(static_cast<double>(static_cast<std::int64_t>(u(8, "int64"))));
            case kUInt8: return number(static_cast<double>(u(1, "uint8")));
            case kUInt16: return number(static_cast<double>(u(2, "uint16")));
            case kReal16: return number(half_to_float(static_cast<std::uint16_t>(u(2, "real16"))));
            case kReal32: return number(bits_to_float(static_cast<std::uint32_t>(u(4, "real32"))));
            case kReal64: return number(bits_to_double(u(8, "real64")));
            case kString:
                out.kind = JsonValue::Kind::string;
                out.text = string_data(keep);
                if (keep) budget_.take(out.text.size());
                return;
            case kTokenRef: out.kind = JsonValue::Kind::string; out.text = token_string(pos); return;
            case kUniformArray: return uniform(out, keep);
            case kArrayBegin:
            case kMapBegin: return container(out, token == kMapBegin, depth, selection);
            default: c_.fail("unknown binary JSON token " + std::to_string(token) + " at " + c_.where(pos));
        }
    }

    void container(JsonValue& out, bool is_map, int depth, const JsonSelection* selection) {
        JsonContainerBuilder builder(out, is_map, selection, budget_);
        while (true) {
            unsigned t = next_token();
            if (t == (is_map ? kMapEnd : kArrayEnd)) break;
            std::string key;
            if (is_map) {
                key = map_key(t);
                t = next_token();
            }
            JsonValue item;
            value(item, t, depth + 1, builder.child_selection(key));
            builder.add(std::move(key), std::move(item));
        }
        builder.finish();
    }

    std::string map_key(unsigned token) {
        if (token == kString) return string_data(true);
        if (token == kTokenRef) return token_string(c_.pos() - 1);
        c_.fail("a binary JSON map key at " + c_.where(c_.pos() - 1) + " is not a string");
    }
};

}  // namespace

JsonValue parse_binary_json(const Source& source, const JsonSelection& selection) {
    return BinaryJsonParser(source).parse_document(selection);
}

}  // namespace io_detail
}  // namespace meniscus
