// VTK XML particle reader: .vtu (UnstructuredGrid) and .vtp (PolyData), as written by ParaView, DualSPHysics,
// SPlisHSPlasH, meshio and pyevtk.
//
// Only <Points> and <PointData> are kept; cells, verts, cell data and field data are skipped. Every DataArray
// encoding VTK writes is read: format="ascii", format="binary" (base64 inline), format="appended" with
// <AppendedData encoding="raw"> or encoding="base64", each optionally compressed with vtkZLibDataCompressor, in
// either byte order and with UInt32 or UInt64 headers. Several <Piece>s are concatenated. Unsupported, each with its
// own message: other compressors (LZ4, LZMA), parallel files (.pvtu / .pvtp, which only reference piece files), and
// the structured dataset types (ImageData, RectilinearGrid, StructuredGrid).
//
// Binary payloads start with a header of header_type words: uncompressed, one word with the byte count; compressed,
// [number of blocks, block size, size of the last block, compressed size of each block]. The header and the data
// may be base64-encoded as one string or as two (VTK itself encodes the compression header on its own), so the
// decoder accepts '=' padding in the middle of a string and simply carries on after it.
//
// Memory: nothing is allocated before the bytes it comes from have been found in the file. Appended arrays may not
// share their start, and each may only read up to the next array's offset, so the arrays together never decode more
// than the file holds (times the zlib cap of max_inflated_size for compressed ones).
#include <algorithm>
#include <map>
#include <memory>

#include "io/io_util.h"

namespace meniscus {
namespace io_detail {
namespace {

constexpr std::size_t kMaxDepth = 256;  // XML nesting; real files use 5 or 6 levels

struct TextRange {
    std::size_t begin = 0, end = 0;
};

enum class Encoding { ascii, binary, appended };

struct DataArrayInfo {
    std::string name;
    std::string type_name;
    ScalarType type = ScalarType::f32;
    bool skip = false;              // String arrays: no float meaning
    std::uint64_t components = 1;
    Encoding encoding = Encoding::ascii;
    std::uint64_t offset = 0;       // appended arrays: from the '_' that starts the appended data
    std::vector<TextRange> text;    // inline arrays: the character data (child elements excluded)
    std::size_t tag_pos = 0;        // for messages
    bool is_points = false;
};

struct PieceInfo {
    std::uint64_t points = 0;
    std::size_t tag_pos = 0;
    bool have_points = false;
    DataArrayInfo positions;
    std::vector<DataArrayInfo> point_data;
};

bool xml_type_from_name(std::string_view name, ScalarType& type) {
    static const struct {
        const char* name;
        ScalarType type;
    } table[] = {
        {"Int8", ScalarType::i8},   {"UInt8", ScalarType::u8},   {"Int16", ScalarType::i16},   {"UInt16", ScalarType::u16},
        {"Int32", ScalarType::i32}, {"UInt32", ScalarType::u32}, {"Int64", ScalarType::i64},   {"UInt64", ScalarType::u64},
        {"Float32", ScalarType::f32}, {"Float64", ScalarType::f64}, {"Char", ScalarType::i8}, {"UChar", ScalarType::u8},
    };
    for (const auto& entry : table)
        if (name == entry.name) {
            type = entry.type;
            return true;
        }
    return false;
}

// Replaces the five predefined XML entities and numeric character references below 128 (names rarely have more).
std::string decode_entities(std::string_view raw) {
    std::string out;
    for (std::size_t i = 0; i < raw.size(); ++i) {
        if (raw[i] != '&') {
            out += raw[i];
            continue;
        }
        std::size_t semi = raw.find(';', i);
        if (semi == std::string_view::npos || semi - i > 8) {
            out += raw[i];
            continue;
        }
        std::string_view entity = raw.substr(i + 1, semi - i - 1);
        char c = 0;
        if (entity == "lt") c = '<';
        else if (entity == "gt") c = '>';
        else if (entity == "amp") c = '&';
        else if (entity == "quot") c = '"';
        else if (entity == "apos") c = '\'';
        else if (entity.size() >= 2 && entity[0] == '#') {
            std::uint64_t code = 0;
            if (entity[1] != 'x' && parse_u64(entity.substr(1), code) && code > 0 && code < 128) c = static_cast<char>(code);
        }
        if (c) {
            out += c;
            i = semi;
        } else {
            out += raw[i];
        }
    }
    return out;
}

struct Tag {
    std::string_view name;
    std::vector<std::pair<std::string_view, std::string_view>> attributes;
    bool closing = false;       // </name>
    bool self_closing = false;  // <name ... />
    std::size_t pos = 0;

    const std::string_view* find(std::string_view key) const {
        for (const auto& a : attributes)
            if (a.first == key) return &a.second;
        return nullptr;
    }
};

// Base64 over a list of text ranges of the file, skipping white space. '=' ends a group of four early and decoding
// goes on after it (see the header comment).
class Base64Stream {
public:
    Base64Stream(const Cursor& c, std::vector<TextRange> ranges, std::string what)
        : c_(c), ranges_(std::move(ranges)), what_(std::move(what)) {
        for (const auto& r : ranges_) chars_left_ += r.end - r.begin;
        if (!ranges_.empty()) pos_ = ranges_[0].begin;
    }

    // An upper bound of the bytes still to come, to check counts before allocating.
    std::uint64_t max_remaining() const { return chars_left_ / 4 * 3 + 3 + (pending_end_ - pending_pos_); }

    void read(unsigned char* out, std::uint64_t n) {
        for (std::uint64_t i = 0; i < n; ++i) {
            if (pending_pos_ == pending_end_ && !refill())
                c_.fail("truncated base64 data in " + what_ + ": it ends after " + std::to_string(decoded_) +
                        " bytes, more were needed");
            out[i] = pending_[pending_pos_++];
            ++decoded_;
        }
    }

private:
    const Cursor& c_;
    std::vector<TextRange> ranges_;
    std::string what_;
    std::size_t range_ = 0, pos_ = 0;
    std::uint64_t chars_left_ = 0, decoded_ = 0;
    unsigned char pending_[3] = {0, 0, 0};
    int pending_pos_ = 0, pending_end_ = 0;

    // Next significant character and its position, or -1 at the end.
    int next_char(std::size_t& at) {
        while (range_ < ranges_.size()) {
            if (pos_ >= ranges_[range_].end) {
                if (++range_ < ranges_.size()) pos_ = ranges_[range_].begin;
                continue;
            }
            unsigned char ch = c_.source().data[pos_];
            at = pos_++;
            --chars_left_;
            if (!Cursor::is_space(ch)) return ch;
        }
        return -1;
    }

    static int sextet(int ch) {
        if (ch >= 'A' && ch <= 'Z') return ch - 'A';
        if (ch >= 'a' && ch <= 'z') return ch - 'a' + 26;
        if (ch >= '0' && ch <= '9') return ch - '0' + 52;
        if (ch == '+') return 62;
        if (ch == '/') return 63;
        return -1;
    }

    bool refill() {
        int values[4];
        int count = 0, padding = 0;
        std::size_t at = 0;
        while (count + padding < 4) {
            int ch = next_char(at);
            if (ch < 0) break;
            if (ch == '=') {
                if (count < 2) c_.fail("bad base64 padding at " + c_.where(at) + " in " + what_);
                ++padding;
                continue;
            }
            if (padding > 0) c_.fail("bad base64 padding at " + c_.where(at) + " in " + what_);
            int v = sextet(ch);
            if (v < 0)
                c_.fail("invalid base64 character " + quote(std::string(1, static_cast<char>(ch))) + " at " + c_.where(at) +
                        " in " + what_);
            values[count++] = v;
        }
        if (count < 2) {
            if (count == 1) c_.fail("truncated base64 data in " + what_ + ": a lone character at " + c_.where(at));
            return false;
        }
        for (int k = count; k < 4; ++k) values[k] = 0;
        std::uint32_t bits = (std::uint32_t(values[0]) << 18) | (std::uint32_t(values[1]) << 12) |
                             (std::uint32_t(values[2]) << 6) | std::uint32_t(values[3]);
        pending_[0] = static_cast<unsigned char>(bits >> 16);
        pending_[1] = static_cast<unsigned char>(bits >> 8);
        pending_[2] = static_cast<unsigned char>(bits);
        pending_pos_ = 0;
        pending_end_ = count - 1;  // 2 characters give 1 byte, 3 give 2, 4 give 3
        return true;
    }
};

// The bytes of one binary payload: a window of the file (raw appended data) or a base64 stream.
class Payload {
public:
    Payload(const Cursor& c, std::size_t begin, std::size_t end, std::string what)
        : c_(c), what_(std::move(what)), pos_(begin), end_(end) {}
    Payload(const Cursor& c, std::vector<TextRange> ranges, std::string what)
        : c_(c), what_(what), base64_(std::make_unique<Base64Stream>(c, std::move(ranges), what)) {}

    std::uint64_t max_remaining() const { return base64_ ? base64_->max_remaining() : end_ - pos_; }

    // n bytes; the pointer stays valid until the next call.
    const unsigned char* take(std::uint64_t n, const std::string& what) {
        if (n > max_remaining()) {
            if (base64_)
                c_.fail(what + " needs " + std::to_string(n) + " bytes but the base64 data of " + what_ + " holds at most " +
                        std::to_string(max_remaining()) + " (a wrong count, or the file is truncated)");
            c_.fail(what + " needs " + std::to_string(n) + " bytes from " + c_.where(pos_) + " but only " +
                    std::to_string(end_ - pos_) + " are available for " + what_ + " (a wrong count, or truncated at " +
                    c_.where(c_.size()) + ")");
        }
        if (!base64_) {
            const unsigned char* p = c_.source().data + pos_;
            pos_ += static_cast<std::size_t>(n);
            return p;
        }
        scratch_.resize(static_cast<std::size_t>(n));
        base64_->read(scratch_.data(), n);
        return scratch_.data();
    }

private:
    const Cursor& c_;
    std::string what_;
    std::size_t pos_ = 0, end_ = 0;
    std::unique_ptr<Base64Stream> base64_;
    Bytes scratch_;
};

class VtuReader {
public:
    explicit VtuReader(const Source& source) : c_(source) {}

    ParticleData read() {
        scan();
        if (!have_root_) c_.fail("not a VTK XML file: no <VTKFile> element");
        if (pieces_.empty()) c_.fail("no <Piece> in the " + dataset_ + " element");
        return assemble();
    }

private:
    Cursor c_;
    bool have_root_ = false;
    std::string dataset_;
    bool big_endian_ = false;
    std::size_t header_size_ = 4;
    bool compressed_ = false;
    std::vector<PieceInfo> pieces_;
    // Appended data: where it starts (just after '_') and ends, and every appended DataArray's offset.
    bool have_appended_ = false, appended_base64_ = false;
    std::size_t appended_begin_ = 0, appended_end_ = 0;
    std::vector<std::uint64_t> appended_offsets_;

    // ---- XML scanning ----

    std::size_t find(std::string_view needle, std::size_t from) const {
        std::string_view all = c_.view(0, c_.size());
        std::size_t at = all.find(needle, from);
        return at == std::string_view::npos ? c_.size() : at;
    }

    [[noreturn]] void fail_at(std::size_t pos, const std::string& what) const { c_.fail(what + " at " + c_.where(pos)); }

    // Parses the tag starting at '<' at `pos`; returns the position after '>'.
    std::size_t parse_tag(std::size_t pos, Tag& tag) {
        const std::size_t size = c_.size();
        const unsigned char* d = c_.source().data;
        tag = Tag{};
        tag.pos = pos;
        std::size_t i = pos + 1;
        if (i < size && d[i] == '/') {
            tag.closing = true;
            ++i;
        }
        auto is_name_char = [](unsigned char ch) {
            return !Cursor::is_space(ch) && ch != '>' && ch != '/' && ch != '=' && ch != '<' && ch != '"' && ch != '\'';
        };
        std::size_t start = i;
        while (i < size && is_name_char(d[i])) ++i;
        if (i == start) fail_at(pos, "malformed XML tag");
        tag.name = c_.view(start, i);
        while (true) {
            while (i < size && Cursor::is_space(d[i])) ++i;
            if (i >= size) c_.fail("truncated at " + c_.where(size) + ": the XML tag <" + std::string(tag.name.substr(0, 40)) +
                                   "> started at " + c_.where(pos) + " is not closed");
            if (d[i] == '>') return i + 1;
            if (d[i] == '/' && i + 1 < size && d[i + 1] == '>' && !tag.closing) {
                tag.self_closing = true;
                return i + 2;
            }
            if (tag.closing) fail_at(i, "unexpected character in the closing tag </" + std::string(tag.name.substr(0, 40)) + ">");
            std::size_t key_start = i;
            while (i < size && is_name_char(d[i])) ++i;
            if (i == key_start) fail_at(i, "malformed attribute in the XML tag <" + std::string(tag.name.substr(0, 40)) + ">");
            std::string_view key = c_.view(key_start, i);
            while (i < size && Cursor::is_space(d[i])) ++i;
            if (i >= size || d[i] != '=') fail_at(i, "attribute " + quote(key) + " without a value");
            ++i;
            while (i < size && Cursor::is_space(d[i])) ++i;
            if (i >= size || (d[i] != '"' && d[i] != '\'')) fail_at(i, "attribute " + quote(key) + " without a quoted value");
            unsigned char q = d[i++];
            std::size_t value_start = i;
            while (i < size && d[i] != q) ++i;
            if (i >= size) c_.fail("truncated at " + c_.where(size) + ": the value of attribute " + quote(key) + " is not closed");
            tag.attributes.emplace_back(key, c_.view(value_start, i));
            ++i;
        }
    }

    void read_root(const Tag& tag) {
        have_root_ = true;
        const std::string_view* type = tag.find("type");
        if (!type) fail_at(tag.pos, "the VTKFile element has no type attribute");
        dataset_ = std::string(*type);
        if (*type == "PUnstructuredGrid" || *type == "PPolyData")
            c_.fail("unsupported VTK XML variant: a parallel " + dataset_ + " file (.pvtu / .pvtp) only lists the piece "
                    "files; read the pieces (.vtu / .vtp) themselves");
        if (*type != "UnstructuredGrid" && *type != "PolyData")
            c_.fail("unsupported VTK XML dataset type " + quote(*type) + " (supported: UnstructuredGrid (.vtu) and "
                    "PolyData (.vtp), the types that hold particles)");
        if (const auto* order = tag.find("byte_order")) {
            if (*order == "BigEndian")
                big_endian_ = true;
            else if (*order != "LittleEndian")
                fail_at(tag.pos, "unknown byte_order " + quote(*order) + " (expected LittleEndian or BigEndian)");
        }
        if (const auto* header = tag.find("header_type")) {
            if (*header == "UInt64")
                header_size_ = 8;
            else if (*header != "UInt32")
                fail_at(tag.pos, "unsupported header_type " + quote(*header) + " (expected UInt32 or UInt64)");
        }
        if (const auto* compressor = tag.find("compressor")) {
            if (*compressor == "vtkZLibDataCompressor")
                compressed_ = true;
            else if (!compressor->empty())
                c_.fail("unsupported VTK XML variant: compressor " + quote(*compressor) +
                        " (only vtkZLibDataCompressor is supported; save without compression or with zlib)");
        }
    }

    DataArrayInfo read_data_array_tag(const Tag& tag, bool is_points) {
        DataArrayInfo a;
        a.tag_pos = tag.pos;
        a.is_points = is_points;
        if (const auto* name = tag.find("Name")) a.name = decode_entities(*name);
        std::string label = is_points ? std::string("the Points DataArray") : "DataArray " + quote(a.name);
        const std::string_view* type = tag.find("type");
        if (!type) fail_at(tag.pos, label + " has no type attribute");
        a.type_name = std::string(*type);
        if (*type == "String") {
            a.skip = true;
        } else if (!xml_type_from_name(*type, a.type)) {
            fail_at(tag.pos, "unsupported type " + quote(*type) + " of " + label +
                                 " (supported: Int8 to UInt64, Float32, Float64; String arrays are skipped)");
        }
        if (const auto* components = tag.find("NumberOfComponents")) {
            if (!parse_u64(*components, a.components) || a.components == 0 || a.components > 65536)
                fail_at(tag.pos, "bad NumberOfComponents " + quote(*components) + " of " + label);
        }
        std::string_view format = "ascii";
        if (const auto* f = tag.find("format")) format = *f;
        if (format == "ascii") {
            a.encoding = Encoding::ascii;
        } else if (format == "binary") {
            a.encoding = Encoding::binary;
        } else if (format == "appended") {
            a.encoding = Encoding::appended;
            const std::string_view* offset = tag.find("offset");
            if (!offset || !parse_u64(*offset, a.offset))
                fail_at(tag.pos, label + " is appended but has no valid offset attribute");
        } else {
            fail_at(tag.pos, "unknown format " + quote(format) + " of " + label + " (expected ascii, binary or appended)");
        }
        return a;
    }

    // One pass over the markup up to <AppendedData>: the root, the pieces and their DataArrays.
    void scan() {
        const std::size_t size = c_.size();
        const unsigned char* d = c_.source().data;
        std::vector<std::string_view> stack;
        DataArrayInfo* open_array = nullptr;  // the kept DataArray whose character data is being collected
        std::size_t array_depth = 0;
        std::size_t i = 0;
        if (size >= 3 && std::memcmp(d, "\xef\xbb\xbf", 3) == 0) i = 3;
        while (i < size) {
            if (d[i] != '<') {
                std::size_t end = i;
                while (end < size && d[end] != '<') ++end;
                if (open_array && stack.size() == array_depth) open_array->text.push_back({i, end});
                i = end;
                continue;
            }
            if (c_.view(i, std::min(size, i + 4)) == "<!--") {
                std::size_t end = find("-->", i + 4);
                if (end >= size) c_.fail("truncated at " + c_.where(size) + ": the XML comment started at " + c_.where(i) + " is not closed");
                i = end + 3;
                continue;
            }
            if (c_.view(i, std::min(size, i + 9)) == "<![CDATA[") {
                std::size_t end = find("]]>", i + 9);
                if (end >= size) c_.fail("truncated at " + c_.where(size) + ": the CDATA section started at " + c_.where(i) + " is not closed");
                if (open_array && stack.size() == array_depth) open_array->text.push_back({i + 9, end});
                i = end + 3;
                continue;
            }
            if (i + 1 < size && (d[i + 1] == '?' || d[i + 1] == '!')) {  // <?xml ...?>, <!DOCTYPE ...>
                std::size_t end = find(">", i);
                if (end >= size) c_.fail("truncated at " + c_.where(size) + ": the XML declaration started at " + c_.where(i) + " is not closed");
                i = end + 1;
                continue;
            }
            Tag tag;
            std::size_t after = parse_tag(i, tag);
            if (tag.closing) {
                if (stack.empty() || stack.back() != tag.name)
                    fail_at(i, "closing tag </" + std::string(tag.name.substr(0, 40)) + "> does not match " +
                                   (stack.empty() ? std::string("any open element") : "<" + std::string(stack.back().substr(0, 40)) + ">"));
                stack.pop_back();
                if (open_array && stack.size() < array_depth) open_array = nullptr;
                i = after;
                continue;
            }
            if (tag.name == "AppendedData") {
                start_appended(tag, after);
                return;  // the rest of the file is data
            }
            handle_start(tag, stack, open_array, array_depth);
            if (!tag.self_closing) {
                if (stack.size() >= kMaxDepth) fail_at(i, "XML nested more than " + std::to_string(kMaxDepth) + " levels deep");
                stack.push_back(tag.name);
                if (open_array && !array_depth) array_depth = stack.size();
            } else if (open_array && !array_depth) {
                open_array = nullptr;  // <DataArray .../> has no data
            }
            i = after;
        }
        if (!stack.empty())
            c_.fail("truncated at " + c_.where(size) + ": the XML element <" + std::string(stack.back().substr(0, 40)) +
                    "> is not closed");
    }

    void handle_start(const Tag& tag, const std::vector<std::string_view>& stack, DataArrayInfo*& open_array,
                      std::size_t& array_depth) {
        const std::string_view parent = stack.empty() ? std::string_view() : stack.back();
        if (stack.empty()) {
            if (tag.name != "VTKFile")
                fail_at(tag.pos, "not a VTK XML file: the root element is <" + std::string(tag.name.substr(0, 40)) + "> instead of <VTKFile>");
            if (have_root_) fail_at(tag.pos, "second VTKFile element");
            read_root(tag);
            return;
        }
        if (tag.name == "Piece" && stack.size() == 2) {
            PieceInfo piece;
            piece.tag_pos = tag.pos;
            const std::string_view* n = tag.find("NumberOfPoints");
            if (!n || !parse_u64(*n, piece.points))
                fail_at(tag.pos, "the Piece element has no valid NumberOfPoints (" + (n ? quote(*n) : std::string("missing")) + ")");
            pieces_.push_back(std::move(piece));
            return;
        }
        if (tag.name != "DataArray") return;
        if (tag.find("format") && *tag.find("format") == "appended") {
            // Every appended array bounds its neighbours' data, kept or not.
            std::uint64_t offset = 0;
            if (const auto* o = tag.find("offset"); o && parse_u64(*o, offset)) appended_offsets_.push_back(offset);
        }
        const bool in_piece = stack.size() == 4 && stack[2] == "Piece" && !pieces_.empty();
        if (!in_piece) return;
        PieceInfo& piece = pieces_.back();
        array_depth = 0;
        if (parent == "Points") {
            if (piece.have_points) fail_at(tag.pos, "second DataArray in Points");
            piece.positions = read_data_array_tag(tag, true);
            piece.have_points = true;
            open_array = &piece.positions;
        } else if (parent == "PointData") {
            piece.point_data.push_back(read_data_array_tag(tag, false));
            open_array = &piece.point_data.back();
        }
    }

    void start_appended(const Tag& tag, std::size_t after) {
        if (have_appended_) fail_at(tag.pos, "second AppendedData element");
        have_appended_ = true;
        std::string_view encoding = "raw";
        if (const auto* e = tag.find("encoding")) encoding = *e;
        if (encoding == "base64")
            appended_base64_ = true;
        else if (encoding != "raw")
            fail_at(tag.pos, "unknown AppendedData encoding " + quote(encoding) + " (expected raw or base64)");
        std::size_t i = after;
        while (i < c_.size() && Cursor::is_space(c_.source().data[i])) ++i;
        if (i >= c_.size() || c_.source().data[i] != '_')
            fail_at(i, "the appended data does not start with '_'" + std::string(i >= c_.size() ? " (file truncated)" : ""));
        appended_begin_ = i + 1;
        // The closing tag is required: arrays that are not read (cells) would otherwise hide a truncated file.
        std::string_view all = c_.view(0, c_.size());
        std::size_t close = appended_base64_ ? all.find('<', appended_begin_)
                                             : all.rfind("</AppendedData>");  // raw data may hold any bytes, this tag too
        if (close == std::string_view::npos || close < appended_begin_ || all.substr(close, 15) != "</AppendedData>")
            c_.fail("truncated at " + c_.where(c_.size()) + ": the AppendedData element started at " + c_.where(tag.pos) +
                    " is not closed by </AppendedData>");
        appended_end_ = close;
    }

    // ---- decoding ----

    std::string label(const DataArrayInfo& a, std::size_t piece) const {
        std::string s = a.is_points ? std::string("Points DataArray") : "DataArray " + quote(a.name);
        return pieces_.size() > 1 ? s + " of piece " + std::to_string(piece) : s;
    }

    std::uint64_t header_word(Payload& payload, const std::string& what) {
        const unsigned char* p = payload.take(header_size_, what);
        if (header_size_ == 4) return big_endian_ ? load_be32(p) : load_le32(p);
        return big_endian_ ? load_be64(p) : load_le64(p);
    }

    // The region of an appended array: from its offset up to the next larger offset of any appended array.
    std::pair<std::size_t, std::size_t> appended_region(const DataArrayInfo& a, const std::string& what) {
        if (!have_appended_) fail_at(a.tag_pos, what + " is appended but the file has no AppendedData (truncated?)");
        const std::uint64_t length = appended_end_ - appended_begin_;
        if (a.offset >= length)
            fail_at(a.tag_pos, what + " has offset " + std::to_string(a.offset) + " beyond the " + std::to_string(length) +
                                   " bytes of appended data (a wrong offset, or truncated at " + c_.where(c_.size()) + ")");
        auto next = std::upper_bound(appended_offsets_.begin(), appended_offsets_.end(), a.offset);
        std::uint64_t end = next == appended_offsets_.end() ? length : std::min<std::uint64_t>(*next, length);
        return {appended_begin_ + static_cast<std::size_t>(a.offset), appended_begin_ + static_cast<std::size_t>(end)};
    }

    std::vector<float> decode_binary(Payload& payload, const DataArrayInfo& a, std::uint64_t count, const std::string& what) {
        const std::size_t size = scalar_size(a.type);
        std::uint64_t expected = 0;
        if (!checked_mul(count, size, expected)) c_.fail(what + ": " + std::to_string(count) + " values is impossibly large");
        std::vector<float> values;
        if (!compressed_) {
            std::uint64_t bytes = header_word(payload, what + " size header");
            if (bytes != expected)
                c_.fail(what + " holds " + std::to_string(bytes) + " bytes but " + std::to_string(count) + " values of type " +
                        a.type_name + " need " + std::to_string(expected) + " (the NumberOfPoints or NumberOfComponents does "
                        "not match the data)");
            const unsigned char* p = payload.take(bytes, what + " data");
            values.resize(static_cast<std::size_t>(count));
            decode_to_float(p, values.size(), a.type, big_endian_, values.data());
            return values;
        }
        std::uint64_t blocks = header_word(payload, what + " compression header");
        if (blocks > payload.max_remaining() / header_size_)
            c_.fail(what + ": compression header claims " + std::to_string(blocks) + " blocks, more than the data can hold");
        std::uint64_t block_size = header_word(payload, what + " compression header");
        std::uint64_t last_size = header_word(payload, what + " compression header");
        std::vector<std::uint64_t> sizes(static_cast<std::size_t>(blocks));
        std::uint64_t compressed_total = 0;
        for (auto& s : sizes) {
            s = header_word(payload, what + " compression header");
            if (s > payload.max_remaining() || compressed_total + s < compressed_total)
                c_.fail(what + ": a compressed block of " + std::to_string(s) + " bytes is larger than the data left");
            compressed_total += s;
        }
        if (last_size > block_size) c_.fail(what + ": the last block (" + std::to_string(last_size) +
                                             " bytes) is larger than the block size " + std::to_string(block_size));
        std::uint64_t total = 0;
        if (blocks > 0) {
            if (!checked_mul(blocks - 1, block_size, total) || total + (last_size ? last_size : block_size) < total)
                c_.fail(what + ": compression header sizes are impossibly large");
            total += last_size ? last_size : block_size;
        }
        if (total != expected)
            c_.fail(what + " decompresses to " + std::to_string(total) + " bytes but " + std::to_string(count) +
                    " values of type " + a.type_name + " need " + std::to_string(expected));
        if (total > max_inflated_size(compressed_total))
            c_.fail(what + ": " + std::to_string(compressed_total) + " compressed bytes claim to hold " + std::to_string(total) +
                    ", beyond any real data; refusing a corrupt file or decompression bomb");
        const unsigned char* p = payload.take(compressed_total, what + " compressed data");
        Bytes raw(static_cast<std::size_t>(total));
        std::uint64_t in = 0, out = 0;
        for (std::size_t b = 0; b < sizes.size(); ++b) {
            std::uint64_t n = b + 1 == sizes.size() && last_size ? last_size : block_size;
            inflate_exact(c_.source().path, p + in, static_cast<std::size_t>(sizes[b]), raw.data() + out, static_cast<std::size_t>(n),
                          15, what + " block " + std::to_string(b));
            in += sizes[b];
            out += n;
        }
        values.resize(static_cast<std::size_t>(count));
        decode_to_float(raw.data(), values.size(), a.type, big_endian_, values.data());
        return values;
    }

    std::vector<float> decode_ascii(const DataArrayInfo& a, std::uint64_t count, const std::string& what) {
        std::uint64_t chars = 0;
        for (const auto& r : a.text) chars += r.end - r.begin;
        if (count > (chars + 1) / 2)
            fail_at(a.tag_pos, what + ": " + std::to_string(count) + " ASCII values cannot fit in its " + std::to_string(chars) +
                                   " characters (NumberOfPoints wrong or file truncated)");
        std::vector<float> values(static_cast<std::size_t>(count));
        std::uint64_t i = 0;
        const unsigned char* d = c_.source().data;
        for (const auto& r : a.text) {
            std::size_t pos = r.begin;
            while (true) {
                while (pos < r.end && Cursor::is_space(d[pos])) ++pos;
                if (pos >= r.end) break;
                std::size_t start = pos;
                while (pos < r.end && !Cursor::is_space(d[pos])) ++pos;
                std::string_view token = c_.view(start, pos);
                if (i == count)
                    fail_at(start, what + " has more than the " + std::to_string(count) + " values NumberOfPoints and "
                                          "NumberOfComponents call for");
                float v = 0.0f;
                if (!parse_float(token, v)) fail_at(start, "bad value " + quote(token) + " in " + what + " (expected a number)");
                values[static_cast<std::size_t>(i++)] = v;
            }
        }
        if (i != count)
            fail_at(a.tag_pos, what + " has only " + std::to_string(i) + " of " + std::to_string(count) + " values (truncated?)");
        return values;
    }

    std::vector<float> decode(const DataArrayInfo& a, std::uint64_t tuples, std::size_t piece) {
        const std::string what = label(a, piece);
        std::uint64_t count = 0;
        if (!checked_mul(tuples, a.components, count)) c_.fail(what + ": size is impossibly large");
        if (a.encoding == Encoding::ascii) return decode_ascii(a, count, what);
        if (a.encoding == Encoding::binary) {
            Payload payload(c_, a.text, what);
            return decode_binary(payload, a, count, what);
        }
        auto region = appended_region(a, what);
        if (appended_base64_) {
            Payload payload(c_, std::vector<TextRange>{{region.first, region.second}}, what);
            return decode_binary(payload, a, count, what);
        }
        Payload payload(c_, region.first, region.second, what);
        return decode_binary(payload, a, count, what);
    }

    ParticleData assemble() {
        std::sort(appended_offsets_.begin(), appended_offsets_.end());
        // Two kept arrays reading the same appended bytes would let a small file claim its size many times over.
        std::map<std::uint64_t, std::string> kept_offsets;
        for (std::size_t p = 0; p < pieces_.size(); ++p) {
            auto check = [&](const DataArrayInfo& a) {
                if (a.encoding != Encoding::appended || a.skip) return;
                auto [it, fresh] = kept_offsets.emplace(a.offset, label(a, p));
                if (!fresh)
                    fail_at(a.tag_pos, label(a, p) + " starts at the same appended offset " + std::to_string(a.offset) + " as " + it->second);
            };
            if (pieces_[p].have_points) check(pieces_[p].positions);
            for (const auto& a : pieces_[p].point_data) check(a);
        }

        ParticleData result;
        for (std::size_t p = 0; p < pieces_.size(); ++p) {
            const PieceInfo& piece = pieces_[p];
            // Parallel writers leave empty pieces, with or without arrays: they add nothing.
            if (piece.points == 0 && p > 0) continue;
            if (!piece.have_points) {
                if (piece.points == 0) continue;
                fail_at(piece.tag_pos, "the Piece has " + std::to_string(piece.points) + " points but no Points DataArray");
            }
            if (piece.positions.skip) fail_at(piece.positions.tag_pos, "the Points DataArray has type String");
            if (piece.positions.components != 3)
                fail_at(piece.positions.tag_pos, "the Points DataArray has " + std::to_string(piece.positions.components) +
                                                     " components instead of 3");
            std::vector<float> positions = decode(piece.positions, piece.points, p);
            if (p == 0) {
                result.positions = std::move(positions);
            } else {
                result.positions.insert(result.positions.end(), positions.begin(), positions.end());
            }
            std::vector<bool> matched(result.attributes.size(), false);
            for (const auto& a : piece.point_data) {
                if (a.skip) continue;
                std::vector<float> values = decode(a, piece.points, p);
                if (p == 0) {
                    Attribute out;
                    out.name = a.name;
                    out.components = static_cast<int>(a.components);
                    out.integral = scalar_is_integer(a.type);
                    out.values = std::move(values);
                    result.attributes.push_back(std::move(out));
                    continue;
                }
                // Later pieces must carry the same arrays as the first, so that every attribute covers every point.
                std::size_t k = 0;
                while (k < result.attributes.size() &&
                       (matched[k] || result.attributes[k].name != a.name || result.attributes[k].components != static_cast<int>(a.components)))
                    ++k;
                if (k == result.attributes.size())
                    fail_at(a.tag_pos, label(a, p) + " with " + std::to_string(a.components) + " components is not in the first piece");
                matched[k] = true;
                result.attributes[k].values.insert(result.attributes[k].values.end(), values.begin(), values.end());
            }
            for (std::size_t k = 0; k < matched.size(); ++k)
                if (!matched[k])
                    fail_at(piece.tag_pos, "piece " + std::to_string(p) + " has no point array " + quote(result.attributes[k].name) +
                                               " (the first piece has it)");
        }
        return result;
    }
};

}  // namespace

ParticleData read_vtu_particles(const Source& source) { return VtuReader(source).read(); }

}  // namespace io_detail
}  // namespace meniscus
