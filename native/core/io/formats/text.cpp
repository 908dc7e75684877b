// Text-table and raw particle readers: CSV with a header row, and XYZ.
//
// CSV: the first line that is neither blank nor a '#' comment is the header; the delimiter is the first of ',', ';'
// and tab found in it, else runs of white space. Columns x, y, z (any case) are the positions, or a 3-column group
// named Points / position / positions / pos (ParaView writes "Points:0", "Points:1", "Points:2"). Other columns
// become attributes: NAME:0 .. NAME:k-1 (ParaView) and NAME_x NAME_y NAME_z group into one k- or 3-component
// attribute, anything else is a scalar. Every value must be a number (nan and inf included); quoted fields are
// unquoted, but a delimiter inside quotes is not supported.
//
// XYZ: raw little-endian float32 x y z triples with no header (the format of splashsurf's .xyz); a file that is all
// printable text is read as lines of three numbers instead. Raw files carry no byte order, so one whose values
// are implausible as little-endian but sane as big-endian is refused as byte-swapped rather than read as garbage.
#include <cmath>

#include "io/io_util.h"
#include "io/mesh_writer.h"

namespace meniscus {
namespace io_detail {
namespace {

std::string_view trim(std::string_view s) {
    while (!s.empty() && Cursor::is_space(static_cast<unsigned char>(s.front()))) s.remove_prefix(1);
    while (!s.empty() && Cursor::is_space(static_cast<unsigned char>(s.back()))) s.remove_suffix(1);
    if (s.size() >= 2 && ((s.front() == '"' && s.back() == '"') || (s.front() == '\'' && s.back() == '\''))) {
        s.remove_prefix(1);
        s.remove_suffix(1);
    }
    return s;
}

// Splits one line by the delimiter (0: runs of white space) into `out`; at most max_fields fields are kept, the
// count of all of them is returned.
std::size_t split_fields(std::string_view line, char delimiter, std::vector<std::string_view>& out, std::size_t max_fields) {
    out.clear();
    std::size_t count = 0;
    if (delimiter == 0) {
        std::size_t i = 0;
        while (true) {
            while (i < line.size() && Cursor::is_space(static_cast<unsigned char>(line[i]))) ++i;
            if (i >= line.size()) break;
            std::size_t start = i;
            while (i < line.size() && !Cursor::is_space(static_cast<unsigned char>(line[i]))) ++i;
            if (count++ < max_fields) out.push_back(trim(line.substr(start, i - start)));
        }
        return count;
    }
    std::size_t start = 0;
    while (true) {
        std::size_t end = line.find(delimiter, start);
        std::string_view field = line.substr(start, end == std::string_view::npos ? std::string_view::npos : end - start);
        if (count++ < max_fields) out.push_back(trim(field));
        if (end == std::string_view::npos) break;
        start = end + 1;
    }
    return count;
}

bool is_blank_or_comment(std::string_view line) {
    std::string_view t = trim(line);
    return t.empty() || t[0] == '#';
}

struct ColumnGroup {
    std::string name;
    std::vector<std::size_t> columns;  // header indices, in component order
};

// Groups header names into attributes: NAME:0 .. NAME:k-1 and NAME_x NAME_y NAME_z.
std::vector<ColumnGroup> group_columns(const std::vector<std::string>& names) {
    std::vector<ColumnGroup> groups;
    auto base_of = [](const std::string& name, const std::string& suffix) -> std::string {
        if (name.size() > suffix.size() && name.compare(name.size() - suffix.size(), suffix.size(), suffix) == 0)
            return name.substr(0, name.size() - suffix.size());
        return std::string();
    };
    for (std::size_t i = 0; i < names.size();) {
        std::string base = base_of(names[i], ":0");
        if (!base.empty()) {
            std::size_t k = 1;
            while (i + k < names.size() && names[i + k] == base + ":" + std::to_string(k)) ++k;
            if (k >= 2) {
                ColumnGroup g{base, {}};
                for (std::size_t j = 0; j < k; ++j) g.columns.push_back(i + j);
                groups.push_back(std::move(g));
                i += k;
                continue;
            }
        }
        base = base_of(names[i], "_x");
        if (!base.empty() && i + 2 < names.size() && names[i + 1] == base + "_y" && names[i + 2] == base + "_z") {
            groups.push_back({base, {i, i + 1, i + 2}});
            i += 3;
            continue;
        }
        groups.push_back({names[i], {i}});
        ++i;
    }
    return groups;
}

// The value with a message that names the line and the column.
float parse_cell(const Cursor& c, std::string_view field, std::size_t line_no, const std::string& column) {
    float v = 0.0f;
    if (parse_float(field, v)) return v;
    if (iequals(field, "nan") || iequals(field, "-nan")) return std::nanf("");
    if (iequals(field, "inf") || iequals(field, "infinity")) return INFINITY;
    if (iequals(field, "-inf") || iequals(field, "-infinity")) return -INFINITY;
    c.fail("line " + std::to_string(line_no) + ", column " + quote(column) + ": " +
           (field.empty() ? std::string("empty value") : "bad value " + quote(field)) + " (expected a number)");
}

// A CSV table: the header's column names, grouped into attributes, and the values read column by column.
class CsvReader {
public:
    explicit CsvReader(const Source& source) : c_(source) {}

    ParticleData read() {
        read_header();
        groups_ = group_columns(names_);
        find_positions();
        read_rows();
        return assemble();
    }

private:
    // A header can only have as many columns as it has characters; a cap keeps a binary file taken for CSV cheap.
    static constexpr std::size_t kMaxColumns = 4096;
    Cursor c_;
    std::size_t line_no_ = 0, header_line_ = 0;
    char delimiter_ = 0;  // 0: runs of white space
    std::vector<std::string> names_;
    std::vector<ColumnGroup> groups_;
    std::size_t pos_columns_[3] = {0, 0, 0};
    std::vector<bool> is_position_;       // per group
    std::vector<std::vector<float>> values_;  // per column, while reading
    std::vector<std::string_view> fields_;

    // The first line that is neither blank nor a comment; its delimiter is the first of ',', ';' and tab in it.
    void read_header() {
        if (c_.remaining() >= 3 && std::memcmp(c_.here(), "\xef\xbb\xbf", 3) == 0) c_.take(3, "byte order mark");
        std::string_view header;
        while (!c_.at_end()) {
            ++line_no_;
            header = c_.line();
            if (!is_blank_or_comment(header)) break;
            header = {};
        }
        if (header.empty()) c_.fail("no header line: a CSV particle file starts with a row of column names including x, y and z");
        header_line_ = line_no_;
        delimiter_ = header.find(',') != std::string_view::npos   ? ','
                     : header.find(';') != std::string_view::npos ? ';'
                     : header.find('\t') != std::string_view::npos ? '\t'
                                                                   : 0;
        const std::size_t columns = split_fields(header, delimiter_, fields_, kMaxColumns);
        if (columns > kMaxColumns) c_.fail("the header has " + std::to_string(columns) + " columns (at most " + std::to_string(kMaxColumns) + ")");
        for (auto f : fields_) names_.emplace_back(f);
    }

    // Columns x, y, z (any case), else a 3-column group named Points / position / positions / pos.
    void find_positions() {
        int gx = -1, gy = -1, gz = -1, gp = -1;
        for (std::size_t g = 0; g < groups_.size(); ++g) {
            const auto& group = groups_[g];
            if (group.columns.size() == 1) {
                if (iequals(group.name, "x") && gx < 0) gx = static_cast<int>(g);
                if (iequals(group.name, "y") && gy < 0) gy = static_cast<int>(g);
                if (iequals(group.name, "z") && gz < 0) gz = static_cast<int>(g);
            } else if (group.columns.size() == 3 && gp < 0) {
                for (const char* n : {"points", "position", "positions", "pos"})
                    if (iequals(group.name, n)) gp = static_cast<int>(g);
            }
        }
        is_position_.assign(groups_.size(), false);
        if (gx >= 0 && gy >= 0 && gz >= 0) {
            const int xyz[3] = {gx, gy, gz};
            for (int k = 0; k < 3; ++k) {
                pos_columns_[k] = groups_[static_cast<std::size_t>(xyz[k])].columns[0];
                is_position_[static_cast<std::size_t>(xyz[k])] = true;
            }
        } else if (gp >= 0) {
            for (int k = 0; k < 3; ++k) pos_columns_[k] = groups_[static_cast<std::size_t>(gp)].columns[static_cast<std::size_t>(k)];
            is_position_[static_cast<std::size_t>(gp)] = true;
        } else {
            std::string list;
            for (std::size_t i = 0; i < names_.size() && i < 20; ++i) list += (i ? ", " : "") + quote(names_[i]);
            c_.fail("the header on line " + std::to_string(header_line_) + " has no columns x, y and z (nor Points:0..2); it has " + list);
        }
    }

    // Column-major while reading, interleaved at the end.
    void read_rows() {
        const std::size_t columns = names_.size();
        values_.resize(columns);
        while (!c_.at_end()) {
            ++line_no_;
            std::string_view line = c_.line();
            if (is_blank_or_comment(line)) continue;
            std::size_t n = split_fields(line, delimiter_, fields_, columns + 1);
            if (n != columns)
                c_.fail("line " + std::to_string(line_no_) + " has " + std::to_string(n) + " fields but the header has " +
                        std::to_string(columns) + (c_.at_end() ? " (truncated?)" : ""));
            for (std::size_t k = 0; k < columns; ++k) values_[k].push_back(parse_cell(c_, fields_[k], line_no_, names_[k]));
        }
    }

    ParticleData assemble() {
        ParticleData out;
        const std::size_t rows = values_.empty() ? 0 : values_[0].size();
        out.positions.resize(3 * rows);
        for (int k = 0; k < 3; ++k) {
            const auto& col = values_[pos_columns_[k]];
            for (std::size_t i = 0; i < rows; ++i) out.positions[3 * i + static_cast<std::size_t>(k)] = col[i];
        }
        for (std::size_t g = 0; g < groups_.size(); ++g) {
            if (is_position_[g]) continue;
            const std::vector<std::size_t>& columns = groups_[g].columns;
            Attribute a;
            a.name = groups_[g].name;
            a.components = static_cast<int>(columns.size());
            a.values.resize(rows * columns.size());
            for (std::size_t j = 0; j < columns.size(); ++j) {
                std::vector<float>& col = values_[columns[j]];
                for (std::size_t i = 0; i < rows; ++i) a.values[i * columns.size() + j] = col[i];
                std::vector<float>().swap(col);  // release as we go: the table is held twice only column by column
            }
            out.attributes.push_back(std::move(a));
        }
        return out;
    }
};

}  // namespace

ParticleData read_csv_particles(const Source& source) { return CsvReader(source).read(); }

namespace {

bool is_text(const Source& s) {
    for (std::size_t i = 0; i < s.size; ++i) {
        unsigned char ch = s.data[i];
        if (!(Cursor::is_space(ch) || (ch >= 32 && ch < 127))) return false;
    }
    return true;
}

ParticleData read_xyz_text(const Source& source) {
    Cursor c(source);
    ParticleData out;
    std::size_t line_no = 0;
    std::vector<std::string_view> fields;
    while (!c.at_end()) {
        ++line_no;
        std::string_view line = c.line();
        if (is_blank_or_comment(line)) continue;
        char delimiter = line.find(',') != std::string_view::npos ? ',' : line.find(';') != std::string_view::npos ? ';' : 0;
        std::size_t n = split_fields(line, delimiter, fields, 4);
        if (n != 3)
            c.fail("line " + std::to_string(line_no) + " has " + std::to_string(n) + " values; a text .xyz file has x y z on "
                   "every line (use CSV with a header for more columns)");
        for (int k = 0; k < 3; ++k) out.positions.push_back(parse_cell(c, fields[static_cast<std::size_t>(k)], line_no, std::string(1, "xyz"[k])));
    }
    return out;
}

// A value no simulation writes: non-finite, beyond 1e15, or a nonzero subnormal-ish magnitude below 1e-30. Byte-
// swapped float32 data is mostly such values.
bool implausible(float v) { return !std::isfinite(v) || std::fabs(v) > 1e15f || (v != 0.0f && std::fabs(v) < 1e-30f); }

}  // namespace

ParticleData read_xyz_particles(const Source& source) {
    if (is_text(source)) return read_xyz_text(source);
    Cursor c(source);
    if (source.size % 12 != 0)
        c.fail("size " + std::to_string(source.size) + " bytes is not a multiple of 12 (3 float32 values per particle): "
               "truncated at " + c.where(source.size) + " after " + std::to_string(source.size / 12) + " whole particles, or not a raw XYZ file");
    const std::size_t values = source.size / 4;
    // Sample up to 30000 values spread over the file for the byte-order check.
    const std::size_t step = std::max<std::size_t>(1, values / 30000);
    std::size_t samples = 0, bad_le = 0, bad_be = 0;
    for (std::size_t i = 0; i < values; i += step) {
        ++samples;
        bad_le += implausible(bits_to_float(load_le32(source.data + 4 * i)));
        bad_be += implausible(bits_to_float(load_be32(source.data + 4 * i)));
    }
    if (bad_le * 4 > samples && bad_be == 0)
        c.fail("the values look byte-swapped: " + std::to_string(bad_le) + " of " + std::to_string(samples) +
               " sampled values are not plausible coordinates as little-endian float32, but all are as big-endian; raw "
               ".xyz files must be little-endian float32 x y z triples");
    ParticleData out;
    out.positions.resize(values);
    decode_to_float(source.data, values, ScalarType::f32, false, out.positions.data());
    return out;
}

// Raw little-endian float32 triples, as splashsurf reads .xyz (attributes have no place in it).
void write_xyz_particles(const ParticleData& particles, const std::string& path) {
    FileWriter out(path);
    for (float x : particles.positions) out.put_le_float(x);
    out.close();
}

}  // namespace io_detail
}  // namespace meniscus
