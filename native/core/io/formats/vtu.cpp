// VTK XML particle reader: .vtu (UnstructuredGrid) and .vtp (PolyData), as written by ParaView, DualSPHysics,
// SPlisHSPlasH, meshio and pyevtk.
//
// Only <Points> and <PointData> are kept; cells, verts, cell data and field data are skipped. Every DataArray
// encoding VTK writes is read (vtu_arrays.cpp): format="ascii", format="binary" (base64 inline), format="appended"
// with <AppendedData encoding="raw"> or encoding="base64", each optionally compressed with vtkZLibDataCompressor, in
// either byte order and with UInt32 or UInt64 headers. Several <Piece>s are concatenated. Unsupported, each with its
// own message: other compressors (LZ4, LZMA), parallel files (.pvtu / .pvtp, which only reference piece files), and
// the structured dataset types (ImageData, RectilinearGrid, StructuredGrid).
//
// The reader makes one pass over the markup (parsers/xml.h) up to <AppendedData>, noting where each kept array's
// data is, then decodes the arrays piece by piece.
#include <algorithm>
#include <map>

#include "io/formats/vtu.h"
#include "io/parsers/xml.h"

namespace meniscus {
namespace io_detail {
namespace vtu {
namespace {

constexpr std::size_t kMaxDepth = 256;  // XML nesting; real files use 5 or 6 levels

bool xml_type_from_name(std::string_view name, ScalarType& type) {
    static const ScalarTypeName table[] = {
        {"Int8", ScalarType::i8},     {"UInt8", ScalarType::u8},     {"Int16", ScalarType::i16}, {"UInt16", ScalarType::u16},
        {"Int32", ScalarType::i32},   {"UInt32", ScalarType::u32},   {"Int64", ScalarType::i64}, {"UInt64", ScalarType::u64},
        {"Float32", ScalarType::f32}, {"Float64", ScalarType::f64}, {"Char", ScalarType::i8},   {"UChar", ScalarType::u8},
    };
    return find_scalar_type(table, name, false, type);
}

// The markup pass: builds the File from the elements that matter, and stops at <AppendedData>.
class Structure : public XmlVisitor {
public:
    explicit Structure(const Cursor& c) : c_(c) {}

    File read() {
        scan_xml(c_, *this, kMaxDepth);
        if (!have_root_) c_.fail("not a VTK XML file: no <VTKFile> element");
        if (file_.pieces.empty()) c_.fail("no <Piece> in the " + file_.dataset + " element");
        std::sort(file_.appended.offsets.begin(), file_.appended.offsets.end());
        return std::move(file_);
    }

    bool start_element(const XmlTag& tag, const std::vector<std::string_view>& open, std::size_t after) override {
        if (tag.name == "AppendedData") {
            read_appended(tag, after);
            return false;  // the rest of the file is data
        }
        if (open.empty())
            read_root(tag);
        else if (tag.name == "Piece" && open.size() == 2)
            read_piece(tag);
        else if (tag.name == "DataArray")
            read_data_array(tag, open);
        return true;
    }

    void end_element(std::string_view, std::size_t depth) override {
        if (open_array_ && depth < array_depth_) open_array_ = nullptr;
    }

    void text(TextRange range, std::size_t depth) override {
        if (open_array_ && depth == array_depth_) open_array_->text.push_back(range);
    }

private:
    const Cursor& c_;
    File file_;
    bool have_root_ = false;
    DataArray* open_array_ = nullptr;  // the kept DataArray whose character data is being collected
    std::size_t array_depth_ = 0;      // the number of open elements inside it (its own included)

    [[noreturn]] void fail_at(std::size_t pos, const std::string& what) const { c_.fail(what + " at " + c_.where(pos)); }

    void read_root(const XmlTag& tag) {
        if (tag.name != "VTKFile")
            fail_at(tag.pos, "not a VTK XML file: the root element is <" + std::string(tag.name.substr(0, 40)) + "> instead of <VTKFile>");
        if (have_root_) fail_at(tag.pos, "second VTKFile element");
        have_root_ = true;
        read_dataset_type(tag);
        FileSettings& s = file_.settings;
        if (const auto* order = tag.find("byte_order")) {
            if (*order == "BigEndian")
                s.big_endian = true;
            else if (*order != "LittleEndian")
                fail_at(tag.pos, "unknown byte_order " + quote(*order) + " (expected LittleEndian or BigEndian)");
        }
        if (const auto* header = tag.find("header_type")) {
            if (*header == "UInt64")
                s.header_size = 8;
            else if (*header != "UInt32")
                fail_at(tag.pos, "unsupported header_type " + quote(*header) + " (expected UInt32 or UInt64)");
        }
        if (const auto* compressor = tag.find("compressor")) {
            if (*compressor == "vtkZLibDataCompressor")
                s.compressed = true;
            else if (!compressor->empty())
                c_.fail("unsupported VTK XML variant: compressor " + quote(*compressor) +
                        " (only vtkZLibDataCompressor is supported; save without compression or with zlib)");
        }
    }

    void read_dataset_type(const XmlTag& tag) {
        const std::string_view* type = tag.find("type");
        if (!type) fail_at(tag.pos, "the VTKFile element has no type attribute");
        file_.dataset = std::string(*type);
        if (*type == "PUnstructuredGrid" || *type == "PPolyData")
            c_.fail("unsupported VTK XML variant: a parallel " + file_.dataset + " file (.pvtu / .pvtp) only lists the piece "
                    "files; read the pieces (.vtu / .vtp) themselves");
        if (*type != "UnstructuredGrid" && *type != "PolyData")
            c_.fail("unsupported VTK XML dataset type " + quote(*type) + " (supported: UnstructuredGrid (.vtu) and "
                    "PolyData (.vtp), the types that hold particles)");
    }

    void read_piece(const XmlTag& tag) {
        Piece piece;
        piece.tag_pos = tag.pos;
        const std::string_view* n = tag.find("NumberOfPoints");
        if (!n || !parse_u64(*n, piece.points))
            fail_at(tag.pos, "the Piece element has no valid NumberOfPoints (" + (n ? quote(*n) : std::string("missing")) + ")");
        file_.pieces.push_back(std::move(piece));
    }

    void read_data_array(const XmlTag& tag, const std::vector<std::string_view>& open) {
        if (tag.find("format") && *tag.find("format") == "appended") {
            // Every appended array bounds its neighbours' data, kept or not.
            std::uint64_t offset = 0;
            if (const auto* o = tag.find("offset"); o && parse_u64(*o, offset)) file_.appended.offsets.push_back(offset);
        }
        const bool in_piece = open.size() == 4 && open[2] == "Piece" && !file_.pieces.empty();
        if (!in_piece) return;
        Piece& piece = file_.pieces.back();
        if (open.back() == "Points") {
            if (piece.have_points) fail_at(tag.pos, "second DataArray in Points");
            piece.positions = data_array(tag, true);
            piece.have_points = true;
            collect_text(tag, &piece.positions, open.size());
        } else if (open.back() == "PointData") {
            piece.point_data.push_back(data_array(tag, false));
            collect_text(tag, &piece.point_data.back(), open.size());
        }
    }

    // Character data directly inside the array's element is its data (an empty element has none).
    void collect_text(const XmlTag& tag, DataArray* array, std::size_t depth) {
        open_array_ = tag.self_closing ? nullptr : array;
        array_depth_ = depth + 1;
    }

    DataArray data_array(const XmlTag& tag, bool is_points) const {
        DataArray a;
        a.tag_pos = tag.pos;
        a.is_points = is_points;
        if (const auto* name = tag.find("Name")) a.name = decode_xml_entities(*name);
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
            if (!offset || !parse_u64(*offset, a.offset)) fail_at(tag.pos, label + " is appended but has no valid offset attribute");
        } else {
            fail_at(tag.pos, "unknown format " + quote(format) + " of " + label + " (expected ascii, binary or appended)");
        }
        return a;
    }

    void read_appended(const XmlTag& tag, std::size_t after) {
        AppendedData& appended = file_.appended;
        if (appended.present) fail_at(tag.pos, "second AppendedData element");
        appended.present = true;
        std::string_view encoding = "raw";
        if (const auto* e = tag.find("encoding")) encoding = *e;
        if (encoding == "base64")
            appended.base64 = true;
        else if (encoding != "raw")
            fail_at(tag.pos, "unknown AppendedData encoding " + quote(encoding) + " (expected raw or base64)");
        std::size_t i = after;
        while (i < c_.size() && Cursor::is_space(c_.source().data[i])) ++i;
        if (i >= c_.size() || c_.source().data[i] != '_')
            fail_at(i, "the appended data does not start with '_'" + std::string(i >= c_.size() ? " (file truncated)" : ""));
        appended.begin = i + 1;
        // The closing tag is required: arrays that are not read (cells) would otherwise hide a truncated file.
        std::string_view all = c_.view(0, c_.size());
        std::size_t close = appended.base64 ? all.find('<', appended.begin)
                                            : all.rfind("</AppendedData>");  // raw data may hold any bytes, this tag too
        if (close == std::string_view::npos || close < appended.begin || all.substr(close, 15) != "</AppendedData>")
            c_.fail("truncated at " + c_.where(c_.size()) + ": the AppendedData element started at " + c_.where(tag.pos) +
                    " is not closed by </AppendedData>");
        appended.end = close;
    }
};

// Concatenates the pieces' points and point arrays; later pieces must carry the first piece's arrays.
class Assembler {
public:
    Assembler(const Cursor& c, const File& file) : c_(c), file_(file) {}

    ParticleData assemble() {
        check_appended_offsets();
        for (std::size_t p = 0; p < file_.pieces.size(); ++p) add_piece(p);
        return std::move(result_);
    }

private:
    const Cursor& c_;
    const File& file_;
    ParticleData result_;

    [[noreturn]] void fail_at(std::size_t pos, const std::string& what) const { c_.fail(what + " at " + c_.where(pos)); }

    std::string label(const DataArray& a, std::size_t piece) const { return array_label(a, piece, file_.pieces.size()); }

    // Two kept arrays reading the same appended bytes would let a small file claim its size many times over.
    void check_appended_offsets() const {
        std::map<std::uint64_t, std::string> kept_offsets;
        auto check = [&](const DataArray& a, std::size_t p) {
            if (a.encoding != Encoding::appended || a.skip) return;
            auto [it, fresh] = kept_offsets.emplace(a.offset, label(a, p));
            if (!fresh) fail_at(a.tag_pos, label(a, p) + " starts at the same appended offset " + std::to_string(a.offset) + " as " + it->second);
        };
        for (std::size_t p = 0; p < file_.pieces.size(); ++p) {
            if (file_.pieces[p].have_points) check(file_.pieces[p].positions, p);
            for (const auto& a : file_.pieces[p].point_data) check(a, p);
        }
    }

    void add_piece(std::size_t p) {
        const Piece& piece = file_.pieces[p];
        // Parallel writers leave empty pieces, with or without arrays: they add nothing.
        if (piece.points == 0 && p > 0) return;
        if (!piece.have_points) {
            if (piece.points == 0) return;
            fail_at(piece.tag_pos, "the Piece has " + std::to_string(piece.points) + " points but no Points DataArray");
        }
        if (piece.positions.skip) fail_at(piece.positions.tag_pos, "the Points DataArray has type String");
        if (piece.positions.components != 3)
            fail_at(piece.positions.tag_pos, "the Points DataArray has " + std::to_string(piece.positions.components) +
                                                 " components instead of 3");
        std::vector<float> positions = decode_array(c_, file_, piece.positions, piece.points, label(piece.positions, p));
        if (p == 0)
            result_.positions = std::move(positions);
        else
            result_.positions.insert(result_.positions.end(), positions.begin(), positions.end());
        std::vector<bool> matched(result_.attributes.size(), false);
        for (const auto& a : piece.point_data) {
            if (a.skip) continue;
            std::vector<float> values = decode_array(c_, file_, a, piece.points, label(a, p));
            if (p == 0)
                add_attribute(a, std::move(values));
            else
                append_to_attribute(a, p, values, matched);
        }
        for (std::size_t k = 0; k < matched.size(); ++k)
            if (!matched[k])
                fail_at(piece.tag_pos, "piece " + std::to_string(p) + " has no point array " + quote(result_.attributes[k].name) +
                                           " (the first piece has it)");
    }

    void add_attribute(const DataArray& a, std::vector<float>&& values) {
        Attribute out;
        out.name = a.name;
        out.components = static_cast<int>(a.components);
        out.integral = scalar_is_integer(a.type);
        out.values = std::move(values);
        result_.attributes.push_back(std::move(out));
    }

    // A later piece's array goes after the first piece's array of the same name and component count.
    void append_to_attribute(const DataArray& a, std::size_t p, const std::vector<float>& values, std::vector<bool>& matched) {
        auto& attributes = result_.attributes;
        std::size_t k = 0;
        while (k < attributes.size() &&
               (matched[k] || attributes[k].name != a.name || attributes[k].components != static_cast<int>(a.components)))
            ++k;
        if (k == attributes.size())
            fail_at(a.tag_pos, label(a, p) + " with " + std::to_string(a.components) + " components is not in the first piece");
        matched[k] = true;
        attributes[k].values.insert(attributes[k].values.end(), values.begin(), values.end());
    }
};

}  // namespace
}  // namespace vtu

ParticleData read_vtu_particles(const Source& source) {
    Cursor c(source);
    const vtu::File file = vtu::Structure(c).read();
    return vtu::Assembler(c, file).assemble();
}

}  // namespace io_detail
}  // namespace meniscus
