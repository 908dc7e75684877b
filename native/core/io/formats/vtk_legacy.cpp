// Legacy VTK parsing. Binary data starts right after the '\n' that ends its header line, so header lines are read
// whole and binary blocks are never preceded by a whitespace skip (their first byte may well be 0x0a or 0x20).
//
// Type sizes follow VTK's own legacy writer on 64-bit Unix: long / unsigned_long are 8 bytes, vtkIdType is written
// as 4-byte int. Cells come in the 4.x layout ("CELLS n size", then n records of a count and that many indices) or
// the 5.x one (OFFSETS and CONNECTIVITY arrays with their own types).
#include "io/formats/vtk_legacy.h"

#include <algorithm>
#include <cmath>

namespace meniscus {
namespace io_detail {
namespace vtk_legacy {
namespace {

using Tokens = std::vector<std::string_view>;

bool vtk_type_from_name(std::string_view name, ScalarType& type) {
    static const ScalarTypeName table[] = {
        {"unsigned_char", ScalarType::u8},   {"char", ScalarType::i8},           {"signed_char", ScalarType::i8},
        {"short", ScalarType::i16},          {"unsigned_short", ScalarType::u16}, {"int", ScalarType::i32},
        {"unsigned_int", ScalarType::u32},   {"long", ScalarType::i64},          {"unsigned_long", ScalarType::u64},
        {"vtktypeint64", ScalarType::i64},   {"vtktypeuint64", ScalarType::u64}, {"vtkidtype", ScalarType::i32},
        {"vtktypeint8", ScalarType::i8},     {"vtktypeuint8", ScalarType::u8},   {"vtktypeint16", ScalarType::i16},
        {"vtktypeuint16", ScalarType::u16},  {"vtktypeint32", ScalarType::i32},  {"vtktypeuint32", ScalarType::u32},
        {"vtktypefloat32", ScalarType::f32}, {"vtktypefloat64", ScalarType::f64}, {"float", ScalarType::f32},
        {"double", ScalarType::f64},
    };
    return find_scalar_type(table, name, true, type);
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

std::string upper(std::string_view s) {
    std::string out(s);
    for (char& ch : out) ch = static_cast<char>(std::toupper(static_cast<unsigned char>(ch)));
    return out;
}

// An integer of an integer type, big-endian; unsigned 64-bit values beyond the signed range saturate (no index is
// that large, and the caller range-checks indices).
std::int64_t decode_integer(const unsigned char* p, ScalarType t) {
    if (t == ScalarType::u64) return static_cast<std::int64_t>(std::min<std::uint64_t>(load_be64(p), INT64_MAX));
    if (t == ScalarType::i64) return static_cast<std::int64_t>(load_be64(p));
    return static_cast<std::int64_t>(decode_scalar(p, t, true));  // exact for every type of 32 bits or fewer
}

// Keyword lines have at most 5 tokens ("TEXTURE_COORDINATES name dim type"); a few more are tolerated and ignored.
constexpr std::size_t kMaxKeywordTokens = 16;

// The value blocks after keyword lines: big-endian binary, or white-space separated ASCII numbers. Every count is
// checked against the bytes left before anything is allocated.
class ArrayReader {
public:
    explicit ArrayReader(Cursor& c) : c_(c) {}
    void set_binary(bool binary) { binary_ = binary; }

    // `count` values of `type` as floats (kept only when `keep` is set; otherwise skipped).
    std::vector<float> floats(ScalarType type, std::uint64_t count, const std::string& what, bool keep) {
        std::vector<float> values;
        if (binary_) {
            const unsigned char* p = binary_block(type, count, what);
            if (keep) {
                values.resize(static_cast<std::size_t>(count));
                decode_to_float(p, values.size(), type, true, values.data());
            }
            return values;
        }
        check_ascii_count(count, what);
        if (keep) values.resize(static_cast<std::size_t>(count));
        for (std::uint64_t i = 0; i < count; ++i) {
            std::string_view token = ascii_token(i, count, what);
            float value = 0.0f;
            if (!parse_float(token, value))
                c_.fail("bad value " + quote(token) + " in " + what + " at " + c_.where(c_.pos() - token.size()) + " (expected a number)");
            if (keep) values[static_cast<std::size_t>(i)] = value;
        }
        return values;
    }

    // `count` values of an integer `type` (cell connectivity), exactly.
    std::vector<std::int64_t> integers(ScalarType type, std::uint64_t count, const std::string& what) {
        if (!scalar_is_integer(type)) c_.fail(what + " has a floating-point type; cell indices must be integers");
        std::vector<std::int64_t> values;
        if (binary_) {
            const unsigned char* p = binary_block(type, count, what);
            values.resize(static_cast<std::size_t>(count));
            for (std::size_t i = 0; i < values.size(); ++i) values[i] = decode_integer(p + i * scalar_size(type), type);
            return values;
        }
        check_ascii_count(count, what);
        values.resize(static_cast<std::size_t>(count));
        for (std::uint64_t i = 0; i < count; ++i) {
            std::string_view token = ascii_token(i, count, what);
            if (!parse_i64(token, values[static_cast<std::size_t>(i)]))
                c_.fail("bad value " + quote(token) + " in " + what + " at " + c_.where(c_.pos() - token.size()) + " (expected an integer)");
        }
        return values;
    }

private:
    Cursor& c_;
    bool binary_ = false;

    const unsigned char* binary_block(ScalarType type, std::uint64_t count, const std::string& what) {
        std::uint64_t bytes = 0;
        if (!checked_mul(count, scalar_size(type), bytes)) c_.fail(what + ": count " + std::to_string(count) + " is impossibly large");
        return c_.take(bytes, what);
    }

    // Every ASCII value takes at least one character plus a separator.
    void check_ascii_count(std::uint64_t count, const std::string& what) const {
        if (count > (std::uint64_t(c_.remaining()) + 1) / 2)
            c_.fail(what + ": " + std::to_string(count) + " ASCII values cannot fit in the " + std::to_string(c_.remaining()) +
                    " bytes left after " + c_.where() + " (count wrong or file truncated)");
    }

    std::string_view ascii_token(std::uint64_t i, std::uint64_t count, const std::string& what) {
        std::string_view token = c_.token();
        if (token.empty())
            c_.fail("truncated at " + c_.where() + ": " + what + " has only " + std::to_string(i) + " of " + std::to_string(count) + " values");
        return token;
    }
};

class Reader {
public:
    Reader(const Source& source, const Options& options) : c_(source), options_(options), arrays_(c_) {}

    Dataset read() {
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
    Options options_;
    ArrayReader arrays_;
    bool binary_ = false;
    bool have_points_ = false;
    bool unstructured_ = false, have_cells_ = false, have_cell_types_ = false;
    std::uint64_t num_points_ = 0;
    enum class Mode { none, point_data, cell_data } mode_ = Mode::none;
    std::uint64_t mode_count_ = 0;  // tuples per array in the current POINT_DATA / CELL_DATA section
    Dataset result_;

    // ---- lines and tokens ----

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
        arrays_.set_binary(binary_);
    }

    // The next non-blank line, split into tokens; empty at the end of the file. Only called where no binary data
    // is pending, so skipping whitespace (the '\n' after a binary block, blank lines) is safe.
    Tokens next_line(std::size_t& line_pos) {
        c_.skip_space();
        line_pos = c_.pos();
        if (c_.at_end()) return {};
        return split_tokens(c_.line(), kMaxKeywordTokens);
    }

    std::uint64_t parse_count(const Tokens& tokens, std::size_t i, const std::string& what, std::size_t line_pos) {
        std::uint64_t value = 0;
        if (i >= tokens.size())
            c_.fail(what + " is missing on the line at " + c_.where(line_pos) + (c_.at_end() ? " (file truncated?)" : ""));
        if (!parse_u64(tokens[i], value))
            c_.fail("bad " + what + " " + quote(tokens[i]) + " at " + c_.where(line_pos) + " (expected a non-negative integer)");
        return value;
    }

    std::uint64_t component_count(const Tokens& tokens, std::size_t i, const std::string& what, std::size_t line_pos) {
        std::uint64_t n = parse_count(tokens, i, what, line_pos);
        if (n == 0 || n > 0x7fffffff)
            c_.fail("bad " + what + " " + std::to_string(n) + " at " + c_.where(line_pos) + " (expected at least 1)");
        return n;
    }

    ScalarType parse_type(const Tokens& tokens, std::size_t i, const std::string& what, std::size_t line_pos) {
        if (i >= tokens.size())
            c_.fail("data type for " + what + " is missing on the line at " + c_.where(line_pos) + (c_.at_end() ? " (file truncated?)" : ""));
        ScalarType type;
        if (iequals(tokens[i], "bit")) c_.fail("unsupported data type 'bit' for " + what + " at " + c_.where(line_pos));
        if (!vtk_type_from_name(tokens[i], type))
            c_.fail("unknown data type " + quote(tokens[i]) + " for " + what + " at " + c_.where(line_pos));
        return type;
    }

    // In binary mode an optional line must be looked for exactly at the cursor; in ASCII mode blank space may precede it.
    bool peek_keyword(std::string_view word) {
        if (!binary_) c_.skip_space();
        return c_.starts_with_word(word);
    }

    // METADATA (VTK 5) runs up to the next blank line.
    void skip_metadata_block() {
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

    // ---- sections ----

    void read_section(const Tokens& tokens, std::size_t line_pos) {
        using Handler = void (Reader::*)(const Tokens&, std::size_t);
        static const struct {
            const char* keyword;
            Handler handler;
        } sections[] = {
            {"DATASET", &Reader::read_dataset},         {"POINTS", &Reader::read_points},
            {"CELLS", &Reader::read_cells},             {"VERTICES", &Reader::read_cells},
            {"LINES", &Reader::read_cells},             {"POLYGONS", &Reader::read_cells},
            {"TRIANGLE_STRIPS", &Reader::read_cells},   {"CELL_TYPES", &Reader::read_cell_types},
            {"POINT_DATA", &Reader::start_point_data},  {"CELL_DATA", &Reader::start_cell_data},
            {"SCALARS", &Reader::read_scalars},         {"VECTORS", &Reader::read_vectors},
            {"NORMALS", &Reader::read_vectors},         {"TENSORS", &Reader::read_vectors},
            {"TENSORS6", &Reader::read_vectors},        {"TEXTURE_COORDINATES", &Reader::read_texture_coordinates},
            {"COLOR_SCALARS", &Reader::read_color_scalars}, {"LOOKUP_TABLE", &Reader::skip_lookup_table},
            {"FIELD", &Reader::read_field},             {"METADATA", &Reader::skip_metadata},
        };
        for (const auto& section : sections)
            if (iequals(tokens[0], section.keyword)) return (this->*section.handler)(tokens, line_pos);
        unknown_keyword(tokens[0], line_pos);
    }

    void skip_metadata(const Tokens&, std::size_t) { skip_metadata_block(); }

    void unknown_keyword(std::string_view keyword, std::size_t line_pos) {
        bool printable = true;
        for (char ch : keyword) printable = printable && static_cast<unsigned char>(ch) >= 32 && static_cast<unsigned char>(ch) < 127;
        c_.fail("unknown keyword " + quote(keyword) + " at " + c_.where(line_pos) +
                (printable ? std::string() : " (binary data where a keyword should be: a count in an earlier section is probably wrong)"));
    }

    void read_dataset(const Tokens& tokens, std::size_t line_pos) {
        if (tokens.size() < 2) c_.fail("DATASET type missing at " + c_.where(line_pos));
        if (!iequals(tokens[1], "UNSTRUCTURED_GRID") && !iequals(tokens[1], "POLYDATA"))
            c_.fail("unsupported DATASET " + quote(tokens[1]) + " (supported: UNSTRUCTURED_GRID, POLYDATA)");
        unstructured_ = iequals(tokens[1], "UNSTRUCTURED_GRID");
        result_.unstructured_grid = unstructured_;
    }

    void read_points(const Tokens& tokens, std::size_t line_pos) {
        if (have_points_) c_.fail("second POINTS section at " + c_.where(line_pos));
        num_points_ = parse_count(tokens, 1, "POINTS count", line_pos);
        ScalarType type = parse_type(tokens, 2, "POINTS", line_pos);
        std::uint64_t count = 0;
        if (!checked_mul(num_points_, 3, count)) c_.fail("POINTS count " + std::to_string(num_points_) + " is impossibly large");
        result_.positions = arrays_.floats(type, count, "POINTS count " + std::to_string(num_points_), true);
        have_points_ = true;
        skip_optional_metadata();
    }

    // CELLS, VERTICES, LINES, POLYGONS or TRIANGLE_STRIPS: "KEYWORD n size", then the cells in the 4.x or 5.x layout.
    void read_cells(const Tokens& tokens, std::size_t line_pos) {
        const std::string keyword = upper(tokens[0]);
        const bool keep = options_.polygons && keyword == "POLYGONS";
        if (options_.polygons && keyword == "TRIANGLE_STRIPS")
            c_.fail("TRIANGLE_STRIPS at " + c_.where(line_pos) + " are not read as mesh faces; write the mesh with POLYGONS");
        if (keep && result_.have_polygons) c_.fail("second POLYGONS section at " + c_.where(line_pos));
        std::uint64_t n = parse_count(tokens, 1, keyword + " count", line_pos);
        std::uint64_t size = parse_count(tokens, 2, keyword + " size", line_pos);
        if (peek_keyword("OFFSETS"))
            read_cells_5x(keyword, n, size, keep);
        else if (keep)
            result_.polygons = polygons_4x(arrays_.integers(ScalarType::i32, size, keyword + " data"), n, size);
        else
            arrays_.floats(ScalarType::i32, size, keyword + " data", false);
        result_.have_polygons = result_.have_polygons || keep;
        have_cells_ = have_cells_ || keyword == "CELLS";
        skip_optional_metadata();
    }

    // VTK 5: "KEYWORD n_offsets n_connectivity", then OFFSETS and CONNECTIVITY arrays with their own types.
    void read_cells_5x(const std::string& keyword, std::uint64_t n, std::uint64_t size, bool keep) {
        std::size_t pos = c_.pos();
        auto offsets_line = split_tokens(c_.line(), kMaxKeywordTokens);
        const ScalarType offsets_type = parse_type(offsets_line, 1, keyword + " OFFSETS", pos);
        std::vector<std::int64_t> offsets;
        if (keep)
            offsets = arrays_.integers(offsets_type, n, keyword + " OFFSETS data");
        else
            arrays_.floats(offsets_type, n, keyword + " OFFSETS data", false);
        skip_optional_metadata();
        auto conn = next_line(pos);
        if (conn.empty() || !iequals(conn[0], "CONNECTIVITY"))
            c_.fail("expected CONNECTIVITY at " + c_.where(pos) + " after the " + keyword + " OFFSETS data" +
                    (conn.empty() ? " (file truncated)" : ", found " + quote(conn[0])));
        const ScalarType conn_type = parse_type(conn, 1, keyword + " CONNECTIVITY", pos);
        if (!keep) {
            arrays_.floats(conn_type, size, keyword + " CONNECTIVITY data", false);
            return;
        }
        std::vector<std::int64_t> connectivity = arrays_.integers(conn_type, size, keyword + " CONNECTIVITY data");
        result_.polygons = polygons_5x(offsets, std::move(connectivity));
    }

    // The 4.x records [count, index...] of `n` polygons that fill exactly `size` values.
    Polygons polygons_4x(const std::vector<std::int64_t>& records, std::uint64_t n, std::uint64_t size) {
        Polygons out;
        std::uint64_t at = 0;
        for (std::uint64_t cell = 0; cell < n; ++cell) {
            const std::int64_t count = at < size ? records[static_cast<std::size_t>(at)] : -1;
            if (count < 0 || static_cast<std::uint64_t>(count) >= size - at)
                c_.fail("POLYGONS cell " + std::to_string(cell) + " runs past the " + std::to_string(size) +
                        " values the POLYGONS line announces (a wrong count or size)");
            out.connectivity.insert(out.connectivity.end(), records.begin() + static_cast<std::ptrdiff_t>(at + 1),
                                    records.begin() + static_cast<std::ptrdiff_t>(at + 1 + count));
            out.offsets.push_back(out.connectivity.size());
            at += 1 + static_cast<std::uint64_t>(count);
        }
        if (at != size)
            c_.fail("POLYGONS has " + std::to_string(n) + " cells in " + std::to_string(at) + " values, but its size says " +
                    std::to_string(size));
        return out;
    }

    // VTK 5 offsets must start at 0, never decrease, and end at the connectivity's size.
    Polygons polygons_5x(const std::vector<std::int64_t>& offsets, std::vector<std::int64_t>&& connectivity) {
        Polygons out;
        out.offsets.clear();
        for (std::size_t i = 0; i < offsets.size(); ++i) {
            const std::int64_t o = offsets[i];
            const bool ok = i == 0 ? o == 0 : o >= offsets[i - 1] && static_cast<std::uint64_t>(o) <= connectivity.size();
            if (!ok) c_.fail("POLYGONS OFFSETS value " + std::to_string(i) + " (" + std::to_string(o) + ") is not a valid offset");
            out.offsets.push_back(static_cast<std::uint64_t>(o));
        }
        if (out.offsets.empty()) out.offsets.push_back(0);
        if (out.offsets.back() != connectivity.size())
            c_.fail("POLYGONS OFFSETS end at " + std::to_string(out.offsets.back()) + " but CONNECTIVITY has " +
                    std::to_string(connectivity.size()) + " values");
        out.connectivity = std::move(connectivity);
        return out;
    }

    void read_cell_types(const Tokens& tokens, std::size_t line_pos) {
        have_cell_types_ = true;
        std::uint64_t n = parse_count(tokens, 1, "CELL_TYPES count", line_pos);
        arrays_.floats(ScalarType::i32, n, "CELL_TYPES data", false);
    }

    void start_point_data(const Tokens& tokens, std::size_t line_pos) {
        std::uint64_t n = parse_count(tokens, 1, "POINT_DATA count", line_pos);
        if (!have_points_) c_.fail("POINT_DATA at " + c_.where(line_pos) + " comes before POINTS");
        if (n != num_points_)
            c_.fail("POINT_DATA count " + std::to_string(n) + " at " + c_.where(line_pos) + " does not match POINTS count " +
                    std::to_string(num_points_));
        mode_ = Mode::point_data;
        mode_count_ = n;
    }

    void start_cell_data(const Tokens& tokens, std::size_t line_pos) {
        mode_count_ = parse_count(tokens, 1, "CELL_DATA count", line_pos);
        mode_ = Mode::cell_data;
    }

    // The decoded name of an attribute section ("SCALARS name type ..."); `label` names the keyword in messages.
    std::string section_name(const Tokens& tokens, std::string_view label, std::size_t line_pos) {
        if (mode_ == Mode::none)
            c_.fail(std::string(tokens[0]) + " at " + c_.where(line_pos) + " comes before any POINT_DATA or CELL_DATA");
        if (tokens.size() < 2) c_.fail(std::string(label) + " name missing at " + c_.where(line_pos));
        return decode_name(tokens[1]);
    }

    void read_scalars(const Tokens& tokens, std::size_t line_pos) {
        std::string name = section_name(tokens, "SCALARS", line_pos);
        std::string what = "SCALARS " + quote(name);
        ScalarType type = parse_type(tokens, 2, what, line_pos);
        std::uint64_t components = tokens.size() > 3 ? component_count(tokens, 3, what + " component count", line_pos) : 1;
        if (peek_keyword("LOOKUP_TABLE")) c_.line();
        read_attribute("SCALARS", name, type, components, what + " data");
    }

    void read_vectors(const Tokens& tokens, std::size_t line_pos) {
        std::string_view keyword = tokens[0];
        std::string name = section_name(tokens, keyword, line_pos);
        std::string what = std::string(keyword) + " " + quote(name);
        ScalarType type = parse_type(tokens, 2, what, line_pos);
        std::uint64_t components = iequals(keyword, "TENSORS") ? 9 : iequals(keyword, "TENSORS6") ? 6 : 3;
        read_attribute(upper(keyword), name, type, components, what + " data");
    }

    void read_texture_coordinates(const Tokens& tokens, std::size_t line_pos) {
        std::string name = section_name(tokens, "TEXTURE_COORDINATES", line_pos);
        std::string what = "TEXTURE_COORDINATES " + quote(name);
        std::uint64_t components = component_count(tokens, 2, what + " dimension", line_pos);
        ScalarType type = parse_type(tokens, 3, what, line_pos);
        read_attribute("TEXTURE_COORDINATES", name, type, components, what + " data");
    }

    // Binary colour scalars are unsigned bytes, ASCII ones floats in [0, 1]; both become floats in [0, 1].
    void read_color_scalars(const Tokens& tokens, std::size_t line_pos) {
        std::string name = section_name(tokens, "COLOR_SCALARS", line_pos);
        std::string what = "COLOR_SCALARS " + quote(name);
        std::uint64_t components = component_count(tokens, 2, what + " component count", line_pos);
        std::uint64_t count = 0;
        if (!checked_mul(mode_count_, components, count)) c_.fail(what + ": size is impossibly large");
        bool keep = mode_ == Mode::point_data;
        auto values = arrays_.floats(binary_ ? ScalarType::u8 : ScalarType::f32, count, what + " data", keep);
        if (binary_)
            for (float& v : values) v /= 255.0f;
        if (keep) add_attribute("COLOR_SCALARS", name, static_cast<int>(components), std::move(values), false);
    }

    // A colour table of its own: 4 values (RGBA) per entry, bytes in binary files.
    void skip_lookup_table(const Tokens& tokens, std::size_t line_pos) {
        std::uint64_t n = parse_count(tokens, 2, "LOOKUP_TABLE size", line_pos);
        std::uint64_t count = 0;
        if (!checked_mul(n, 4, count)) c_.fail("LOOKUP_TABLE size " + std::to_string(n) + " is impossibly large");
        arrays_.floats(binary_ ? ScalarType::u8 : ScalarType::f32, count, "LOOKUP_TABLE data", false);
    }

    // One attribute array of the current POINT_DATA / CELL_DATA section (cell data is skipped).
    void read_attribute(const std::string& section, const std::string& name, ScalarType type, std::uint64_t components,
                        const std::string& what) {
        std::uint64_t count = 0;
        if (!checked_mul(mode_count_, components, count)) c_.fail(what + ": size is impossibly large");
        bool keep = mode_ == Mode::point_data;
        auto values = arrays_.floats(type, count, what, keep);
        if (keep) add_attribute(section, name, static_cast<int>(components), std::move(values), scalar_is_integer(type));
        skip_optional_metadata();
    }

    void read_field(const Tokens& tokens, std::size_t line_pos) {
        std::uint64_t arrays = parse_count(tokens, 2, "FIELD array count", line_pos);
        // Each array needs at least a header line of a few bytes: no real file has more arrays than that.
        if (arrays > c_.remaining() / 8 + 1)
            c_.fail("FIELD array count " + std::to_string(arrays) + " at " + c_.where(line_pos) + " cannot fit in the " +
                    std::to_string(c_.remaining()) + " bytes left");
        for (std::uint64_t k = 0; k < arrays; ++k) {
            skip_optional_metadata();
            std::size_t pos = 0;
            auto array = next_line(pos);
            if (array.empty())
                c_.fail("truncated at " + c_.where() + ": FIELD has only " + std::to_string(k) + " of " + std::to_string(arrays) + " arrays");
            if (array[0] == "NULL_ARRAY") continue;  // written by VTK for missing arrays, no data follows
            read_field_array(array, pos);
        }
        skip_optional_metadata();
    }

    // "name components tuples type", then the values.
    void read_field_array(const Tokens& array, std::size_t pos) {
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
        auto values = arrays_.floats(type, count, what + " data", keep);
        if (keep) add_attribute("FIELD", name, static_cast<int>(components), std::move(values), scalar_is_integer(type));
    }

    void add_attribute(const std::string& section, const std::string& name, int components, std::vector<float>&& values, bool integral) {
        PointArray array;
        array.section = section;
        array.attribute.name = name;
        array.attribute.components = components;
        array.attribute.values = std::move(values);
        array.attribute.integral = integral;
        result_.point_data.push_back(std::move(array));
    }
};

}  // namespace

Dataset read(const Source& source, const Options& options) { return Reader(source, options).read(); }

}  // namespace vtk_legacy
}  // namespace io_detail
}  // namespace meniscus
