// Legacy VTK particle reader (file format versions 2.0 to 5.1, ASCII and big-endian BINARY).
//
// Only the points and their POINT_DATA are kept; cells (both the 4.x "CELLS n size" layout and the 5.x OFFSETS /
// CONNECTIVITY layout), CELL_DATA, dataset-level FIELD data, lookup tables and METADATA blocks are parsed only to be
// skipped. Binary data starts right after the '\n' that ends its header line, so header lines are read whole and
// binary blocks are never preceded by a whitespace skip (their first byte may well be 0x0a or 0x20).
//
// Type sizes follow VTK's own legacy writer on 64-bit Unix: long / unsigned_long are 8 bytes, vtkIdType is written
// as 4-byte int.
#include <cmath>

#include "io/io_util.h"

namespace meniscus {
namespace io_detail {
namespace {

bool vtk_type_from_name(std::string_view name, ScalarType& type) {
    static const struct {
        const char* name;
        ScalarType type;
    } table[] = {
        {"unsigned_char", ScalarType::u8},   {"char", ScalarType::i8},           {"signed_char", ScalarType::i8},
        {"short", ScalarType::i16},          {"unsigned_short", ScalarType::u16}, {"int", ScalarType::i32},
        {"unsigned_int", ScalarType::u32},   {"long", ScalarType::i64},          {"unsigned_long", ScalarType::u64},
        {"vtktypeint64", ScalarType::i64},   {"vtktypeuint64", ScalarType::u64}, {"vtkidtype", ScalarType::i32},
        {"vtktypeint8", ScalarType::i8},     {"vtktypeuint8", ScalarType::u8},   {"vtktypeint16", ScalarType::i16},
        {"vtktypeuint16", ScalarType::u16},  {"vtktypeint32", ScalarType::i32},  {"vtktypeuint32", ScalarType::u32},
        {"vtktypefloat32", ScalarType::f32}, {"vtktypefloat64", ScalarType::f64}, {"float", ScalarType::f32},
        {"double", ScalarType::f64},
    };
    for (const auto& entry : table)
        if (iequals(name, entry.name)) {
            type = entry.type;
            return true;
        }
    return false;
}

int hex_digit(char c) {
    if (c >= '0' && c <= '9') return c - '0';
    if (c >= 'a' && c <= 'f') return c - 'a' + 10;
    if (c >= 'A' && c <= 'F') return c - 'A' + 10;
    return -1;
}

// VTK writes names with spaces and other special characters as %XX.
std::string decode_name(std::string_view raw) {
    std::string out;
    for (std::size_t i = 0; i < raw.size(); ++i) {
        if (raw[i] == '%' && i + 2 < raw.size()) {
            int hi = hex_digit(raw[i + 1]), lo = hex_digit(raw[i + 2]);
            if (hi >= 0 && lo >= 0) {
                out += static_cast<char>(hi * 16 + lo);
                i += 2;
                continue;
            }
        }
        out += raw[i];
    }
    return out;
}

// Converts n big-endian values of type t at p to float; the switch sits outside the loop so that the common
// float case is a tight loop.
void decode_be_values(const unsigned char* p, std::size_t n, ScalarType t, float* out) {
    const std::size_t size = scalar_size(t);
    switch (t) {
        case ScalarType::f32:
            for (std::size_t i = 0; i < n; ++i) out[i] = bits_to_float(load_be32(p + 4 * i));
            break;
        case ScalarType::i32:
            for (std::size_t i = 0; i < n; ++i) out[i] = static_cast<float>(static_cast<std::int32_t>(load_be32(p + 4 * i)));
            break;
        default:
            for (std::size_t i = 0; i < n; ++i) out[i] = static_cast<float>(decode_scalar(p + size * i, t, true));
            break;
    }
}

// Keyword lines have at most 5 tokens ("TEXTURE_COORDINATES name dim type"); a few more are tolerated and ignored.
constexpr std::size_t kMaxKeywordTokens = 16;

class VtkReader {
public:
    explicit VtkReader(const Source& source) : c_(source) {}

    ParticleData read() {
        read_header();
        while (true) {
            std::size_t line_pos = 0;
            auto tokens = next_line(line_pos);
            if (tokens.empty()) break;
            read_section(tokens, line_pos);
        }
        if (!have_points_) c_.fail("no POINTS section (expected DATASET UNSTRUCTURED_GRID or POLYDATA with POINTS)");
        // An unstructured grid always writes CELL_TYPES after CELLS: a file ending in between was cut short,
        // and its point data (velocities, ids) would silently be missing.
        if (unstructured_ && have_cells_ && !have_cell_types_)
            c_.fail("truncated at " + c_.where() + ": UNSTRUCTURED_GRID has CELLS but no CELL_TYPES");
        return std::move(result_);
    }

private:
    Cursor c_;
    bool binary_ = false;
    bool have_points_ = false;
    bool unstructured_ = false, have_cells_ = false, have_cell_types_ = false;
    std::uint64_t num_points_ = 0;
    enum class Mode { none, point_data, cell_data } mode_ = Mode::none;
    std::uint64_t mode_count_ = 0;  // tuples per array in the current POINT_DATA / CELL_DATA section
    ParticleData result_;

    void read_header() {
        std::string_view first = c_.line();
        if (first.substr(0, 14) != "# vtk DataFile")
            c_.fail("not a legacy VTK file: the first line is " + quote(first) + " instead of '# vtk DataFile Version x.y'");
        if (c_.at_end()) c_.fail("truncated at " + c_.where() + ": the title line is missing");
        c_.line();  // title: free text, may be empty
        std::size_t pos = c_.pos();
        auto tokens = split_tokens(c_.line(), kMaxKeywordTokens);
        if (tokens.empty() && c_.at_end()) c_.fail("truncated at " + c_.where() + ": the ASCII / BINARY line is missing");
        if (tokens.size() == 1 && iequals(tokens[0], "ASCII"))
            binary_ = false;
        else if (tokens.size() == 1 && iequals(tokens[0], "BINARY"))
            binary_ = true;
        else
            c_.fail("expected ASCII or BINARY at " + c_.where(pos) + ", found " + quote(tokens.empty() ? "" : tokens[0]));
    }

    // The next non-blank line, split into tokens; empty at the end of the file. Only called where no binary data
    // is pending, so skipping whitespace (the '\n' after a binary block, blank lines) is safe.
    std::vector<std::string_view> next_line(std::size_t& line_pos) {
        c_.skip_space();
        line_pos = c_.pos();
        if (c_.at_end()) return {};
        return split_tokens(c_.line(), kMaxKeywordTokens);
    }

    std::uint64_t parse_count(const std::vector<std::string_view>& tokens, std::size_t i, const std::string& what,
                              std::size_t line_pos) {
        std::uint64_t value = 0;
        if (i >= tokens.size())
            c_.fail(what + " is missing on the line at " + c_.where(line_pos) + (c_.at_end() ? " (file truncated?)" : ""));
        if (!parse_u64(tokens[i], value))
            c_.fail("bad " + what + " " + quote(tokens[i]) + " at " + c_.where(line_pos) + " (expected a non-negative integer)");
        return value;
    }

    ScalarType parse_type(const std::vector<std::string_view>& tokens, std::size_t i, const std::string& what,
                          std::size_t line_pos) {
        if (i >= tokens.size())
            c_.fail("data type for " + what + " is missing on the line at " + c_.where(line_pos) +
                    (c_.at_end() ? " (file truncated?)" : ""));
        ScalarType type;
        if (iequals(tokens[i], "bit")) c_.fail("unsupported data type 'bit' for " + what + " at " + c_.where(line_pos));
        if (!vtk_type_from_name(tokens[i], type))
            c_.fail("unknown data type " + quote(tokens[i]) + " for " + what + " at " + c_.where(line_pos));
        return type;
    }

    // Reads `count` values of `type` (kept as float when keep is set, otherwise skipped). The count is checked
    // against the bytes left before anything is allocated.
    std::vector<float> read_array(ScalarType type, std::uint64_t count, const std::string& what, bool keep) {
        std::vector<float> values;
        if (binary_) {
            std::uint64_t bytes = 0;
            if (!checked_mul(count, scalar_size(type), bytes))
                c_.fail(what + ": count " + std::to_string(count) + " is impossibly large");
            const unsigned char* p = c_.take(bytes, what);
            if (keep) {
                values.resize(static_cast<std::size_t>(count));
                decode_be_values(p, values.size(), type, values.data());
            }
            return values;
        }
        // ASCII: every value takes at least one character plus a separator.
        if (count > (std::uint64_t(c_.remaining()) + 1) / 2)
            c_.fail(what + ": " + std::to_string(count) + " ASCII values cannot fit in the " +
                    std::to_string(c_.remaining()) + " bytes left after " + c_.where() + " (count wrong or file truncated)");
        if (keep) values.resize(static_cast<std::size_t>(count));
        for (std::uint64_t i = 0; i < count; ++i) {
            std::string_view token = c_.token();
            if (token.empty())
                c_.fail("truncated at " + c_.where() + ": " + what + " has only " + std::to_string(i) + " of " +
                        std::to_string(count) + " values");
            float value = 0.0f;
            if (!parse_float(token, value))
                c_.fail("bad value " + quote(token) + " in " + what + " at " + c_.where(c_.pos() - token.size()) +
                        " (expected a number)");
            if (keep) values[static_cast<std::size_t>(i)] = value;
        }
        return values;
    }

    // In binary mode an optional line must be looked for exactly at the cursor; in ASCII mode blank space may precede it.
    bool peek_keyword(std::string_view word) {
        if (!binary_) c_.skip_space();
        return c_.starts_with_word(word);
    }

    void skip_metadata_block() {
        // METADATA (VTK 5) runs up to the next blank line.
        while (!c_.at_end()) {
            auto tokens = split_tokens(c_.line(), kMaxKeywordTokens);
            if (tokens.empty()) break;
        }
    }

    // Only called right after a data block has been consumed, so skipping whitespace cannot eat binary data;
    // the position is restored when no METADATA follows.
    void skip_optional_metadata() {
        while (true) {
            std::size_t pos = c_.pos();
            c_.skip_space();
            if (!c_.starts_with_word("METADATA")) {
                c_.seek(pos);
                return;
            }
            c_.line();
            skip_metadata_block();
        }
    }

    void add_attribute(const std::string& name, int components, std::vector<float>&& values, bool integral = false) {
        Attribute a;
        a.name = name;
        a.components = components;
        a.values = std::move(values);
        a.integral = integral;
        result_.attributes.push_back(std::move(a));
    }

    void require_data_section(std::string_view keyword, std::size_t line_pos) {
        if (mode_ == Mode::none)
            c_.fail(std::string(keyword) + " at " + c_.where(line_pos) + " comes before any POINT_DATA or CELL_DATA");
    }

    std::uint64_t component_count(const std::vector<std::string_view>& tokens, std::size_t i, const std::string& what,
                                  std::size_t line_pos) {
        std::uint64_t n = parse_count(tokens, i, what, line_pos);
        if (n == 0 || n > 0x7fffffff)
            c_.fail("bad " + what + " " + std::to_string(n) + " at " + c_.where(line_pos) + " (expected at least 1)");
        return n;
    }

    // One attribute array of the current POINT_DATA / CELL_DATA section.
    void read_attribute(const std::string& name, ScalarType type, std::uint64_t components, const std::string& what) {
        std::uint64_t count = 0;
        if (!checked_mul(mode_count_, components, count)) c_.fail(what + ": size is impossibly large");
        bool keep = mode_ == Mode::point_data;
        auto values = read_array(type, count, what, keep);
        if (keep) add_attribute(name, static_cast<int>(components), std::move(values), scalar_is_integer(type));
        skip_optional_metadata();
    }

    void skip_cells(const std::vector<std::string_view>& tokens, std::size_t line_pos) {
        std::string keyword(tokens[0]);
        for (char& ch : keyword) ch = static_cast<char>(std::toupper(static_cast<unsigned char>(ch)));
        std::uint64_t n = parse_count(tokens, 1, keyword + " count", line_pos);
        std::uint64_t size = parse_count(tokens, 2, keyword + " size", line_pos);
        if (peek_keyword("OFFSETS")) {
            // VTK 5: "CELLS n_offsets n_connectivity", then OFFSETS and CONNECTIVITY arrays with their own types.
            std::size_t pos = c_.pos();
            auto offsets = split_tokens(c_.line(), kMaxKeywordTokens);
            read_array(parse_type(offsets, 1, keyword + " OFFSETS", pos), n, keyword + " OFFSETS data", false);
            skip_optional_metadata();
            auto conn = next_line(pos);
            if (conn.empty() || !iequals(conn[0], "CONNECTIVITY"))
                c_.fail("expected CONNECTIVITY at " + c_.where(pos) + " after the " + keyword + " OFFSETS data" +
                        (conn.empty() ? " (file truncated)" : ", found " + quote(conn[0])));
            read_array(parse_type(conn, 1, keyword + " CONNECTIVITY", pos), size, keyword + " CONNECTIVITY data", false);
        } else {
            read_array(ScalarType::i32, size, keyword + " data", false);
        }
        skip_optional_metadata();
    }

    void read_field(const std::vector<std::string_view>& tokens, std::size_t line_pos) {
        std::uint64_t arrays = parse_count(tokens, 2, "FIELD array count", line_pos);
        // Each array needs at least a header line of a few bytes: no real file has more arrays than that.
        if (arrays > c_.remaining() / 8 + 1)
            c_.fail("FIELD array count " + std::to_string(arrays) + " at " + c_.where(line_pos) +
                    " cannot fit in the " + std::to_string(c_.remaining()) + " bytes left");
        for (std::uint64_t k = 0; k < arrays; ++k) {
            skip_optional_metadata();
            std::size_t pos = 0;
            auto array = next_line(pos);
            if (array.empty())
                c_.fail("truncated at " + c_.where() + ": FIELD has only " + std::to_string(k) + " of " +
                        std::to_string(arrays) + " arrays");
            if (array[0] == "NULL_ARRAY") continue;  // written by VTK for missing arrays, no data follows
            std::string name = decode_name(array[0]);
            std::string what = "FIELD array " + quote(name);
            std::uint64_t components = component_count(array, 1, what + " component count", pos);
            std::uint64_t tuples = parse_count(array, 2, what + " tuple count", pos);
            ScalarType type = parse_type(array, 3, what, pos);
            std::uint64_t count = 0;
            if (!checked_mul(components, tuples, count)) c_.fail(what + ": size is impossibly large");
            bool keep = mode_ == Mode::point_data;
            if (keep && tuples != num_points_)
                c_.fail(what + " at " + c_.where(pos) + " has " + std::to_string(tuples) + " tuples but there are " +
                        std::to_string(num_points_) + " points");
            auto values = read_array(type, count, what + " data", keep);
            if (keep) add_attribute(name, static_cast<int>(components), std::move(values), scalar_is_integer(type));
        }
        skip_optional_metadata();
    }

    void read_section(const std::vector<std::string_view>& tokens, std::size_t line_pos) {
        std::string_view keyword = tokens[0];
        auto is = [&](const char* word) { return iequals(keyword, word); };

        if (is("DATASET")) {
            if (tokens.size() < 2) c_.fail("DATASET type missing at " + c_.where(line_pos));
            if (!iequals(tokens[1], "UNSTRUCTURED_GRID") && !iequals(tokens[1], "POLYDATA"))
                c_.fail("unsupported DATASET " + quote(tokens[1]) + " (supported: UNSTRUCTURED_GRID, POLYDATA)");
            unstructured_ = iequals(tokens[1], "UNSTRUCTURED_GRID");
        } else if (is("POINTS")) {
            if (have_points_) c_.fail("second POINTS section at " + c_.where(line_pos));
            num_points_ = parse_count(tokens, 1, "POINTS count", line_pos);
            ScalarType type = parse_type(tokens, 2, "POINTS", line_pos);
            std::uint64_t count = 0;
            if (!checked_mul(num_points_, 3, count)) c_.fail("POINTS count " + std::to_string(num_points_) + " is impossibly large");
            std::string what = "POINTS count " + std::to_string(num_points_);
            result_.positions = read_array(type, count, what, true);
            have_points_ = true;
            skip_optional_metadata();
        } else if (is("CELLS") || is("VERTICES") || is("LINES") || is("POLYGONS") || is("TRIANGLE_STRIPS")) {
            skip_cells(tokens, line_pos);
            have_cells_ = have_cells_ || is("CELLS");
        } else if (is("CELL_TYPES")) {
            have_cell_types_ = true;
            std::uint64_t n = parse_count(tokens, 1, "CELL_TYPES count", line_pos);
            read_array(ScalarType::i32, n, "CELL_TYPES data", false);
        } else if (is("POINT_DATA")) {
            std::uint64_t n = parse_count(tokens, 1, "POINT_DATA count", line_pos);
            if (!have_points_) c_.fail("POINT_DATA at " + c_.where(line_pos) + " comes before POINTS");
            if (n != num_points_)
                c_.fail("POINT_DATA count " + std::to_string(n) + " at " + c_.where(line_pos) + " does not match POINTS count " +
                        std::to_string(num_points_));
            mode_ = Mode::point_data;
            mode_count_ = n;
        } else if (is("CELL_DATA")) {
            mode_count_ = parse_count(tokens, 1, "CELL_DATA count", line_pos);
            mode_ = Mode::cell_data;
        } else if (is("SCALARS")) {
            require_data_section(keyword, line_pos);
            if (tokens.size() < 2) c_.fail("SCALARS name missing at " + c_.where(line_pos));
            std::string name = decode_name(tokens[1]);
            std::string what = "SCALARS " + quote(name);
            ScalarType type = parse_type(tokens, 2, what, line_pos);
            std::uint64_t components = tokens.size() > 3 ? component_count(tokens, 3, what + " component count", line_pos) : 1;
            if (peek_keyword("LOOKUP_TABLE")) c_.line();
            read_attribute(name, type, components, what + " data");
        } else if (is("VECTORS") || is("NORMALS") || is("TENSORS") || is("TENSORS6")) {
            require_data_section(keyword, line_pos);
            if (tokens.size() < 2) c_.fail(std::string(keyword) + " name missing at " + c_.where(line_pos));
            std::string name = decode_name(tokens[1]);
            std::string what = std::string(keyword) + " " + quote(name);
            ScalarType type = parse_type(tokens, 2, what, line_pos);
            std::uint64_t components = is("TENSORS") ? 9 : is("TENSORS6") ? 6 : 3;
            read_attribute(name, type, components, what + " data");
        } else if (is("TEXTURE_COORDINATES")) {
            require_data_section(keyword, line_pos);
            if (tokens.size() < 2) c_.fail("TEXTURE_COORDINATES name missing at " + c_.where(line_pos));
            std::string name = decode_name(tokens[1]);
            std::string what = "TEXTURE_COORDINATES " + quote(name);
            std::uint64_t components = component_count(tokens, 2, what + " dimension", line_pos);
            ScalarType type = parse_type(tokens, 3, what, line_pos);
            read_attribute(name, type, components, what + " data");
        } else if (is("COLOR_SCALARS")) {
            // Binary colour scalars are unsigned bytes, ASCII ones floats in [0, 1]; both become floats in [0, 1].
            require_data_section(keyword, line_pos);
            if (tokens.size() < 2) c_.fail("COLOR_SCALARS name missing at " + c_.where(line_pos));
            std::string name = decode_name(tokens[1]);
            std::string what = "COLOR_SCALARS " + quote(name);
            std::uint64_t components = component_count(tokens, 2, what + " component count", line_pos);
            std::uint64_t count = 0;
            if (!checked_mul(mode_count_, components, count)) c_.fail(what + ": size is impossibly large");
            bool keep = mode_ == Mode::point_data;
            auto values = read_array(binary_ ? ScalarType::u8 : ScalarType::f32, count, what + " data", keep);
            if (binary_)
                for (float& v : values) v /= 255.0f;
            if (keep) add_attribute(name, static_cast<int>(components), std::move(values));
        } else if (is("LOOKUP_TABLE")) {
            // A colour table of its own: 4 values (RGBA) per entry, bytes in binary files.
            std::uint64_t n = parse_count(tokens, 2, "LOOKUP_TABLE size", line_pos);
            std::uint64_t count = 0;
            if (!checked_mul(n, 4, count)) c_.fail("LOOKUP_TABLE size " + std::to_string(n) + " is impossibly large");
            read_array(binary_ ? ScalarType::u8 : ScalarType::f32, count, "LOOKUP_TABLE data", false);
        } else if (is("FIELD")) {
            read_field(tokens, line_pos);
        } else if (is("METADATA")) {
            skip_metadata_block();
        } else {
            bool printable = true;
            for (char ch : keyword) printable = printable && static_cast<unsigned char>(ch) >= 32 && static_cast<unsigned char>(ch) < 127;
            c_.fail("unknown keyword " + quote(keyword) + " at " + c_.where(line_pos) +
                    (printable ? std::string() : " (binary data where a keyword should be: a count in an earlier section is probably wrong)"));
        }
    }
};

}  // namespace

ParticleData read_vtk_particles(const Source& source) { return VtkReader(source).read(); }

}  // namespace io_detail
}  // namespace meniscus
