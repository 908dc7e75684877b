// The .npy format: a magic, a header that is a Python dict literal (descr, fortran_order, shape), then the raw data.
#include "io/formats/npy.h"

#include <memory>

#include "io/parsers/half_float.h"
#include "io/parsers/python_literal.h"

namespace meniscus {
namespace io_detail {
namespace {

// ---- dtypes --------------------------------------------------------------------------------------------------

struct DType {
    enum class Kind { number, half, skip, structured } kind = Kind::skip;
    ScalarType type = ScalarType::f32;
    bool big_endian = false;
    std::uint64_t size = 0;  // bytes per element
    std::string text;        // as written, for messages
    struct Field {
        std::string name;
        DType* type = nullptr;
        std::uint64_t offset = 0;
        std::uint64_t count = 1;  // product of the subarray shape
    };
    std::vector<Field> fields;
    std::vector<std::unique_ptr<DType>> owned;

    bool numeric() const { return kind == Kind::number || kind == Kind::half; }
};

// Converts n elements of a numeric dtype, `stride` bytes apart, to float.
void convert(const unsigned char* p, std::size_t n, std::size_t stride, const DType& t, float* out, std::size_t out_stride) {
    if (t.kind == DType::Kind::half) {
        for (std::size_t i = 0; i < n; ++i) {
            const unsigned char* q = p + i * stride;
            out[i * out_stride] = half_to_float(t.big_endian ? load_be16(q) : load_le16(q));
        }
        return;
    }
    if (stride == t.size && out_stride == 1) {
        decode_to_float(p, n, t.type, t.big_endian, out);
        return;
    }
    for (std::size_t i = 0; i < n; ++i) out[i * out_stride] = static_cast<float>(decode_scalar(p + i * stride, t.type, t.big_endian));
}

class NpyParser {
public:
    explicit NpyParser(const Source& source) : c_(source) {}

    NpyArray parse() {
        const std::size_t header_pos = read_preamble();
        const PyValue dict = read_header_dict(header_pos);
        const PyValue* descr = dict.get("descr");
        const PyValue* fortran = dict.get("fortran_order");
        const PyValue* shape = dict.get("shape");
        if (!descr || !fortran || !shape)
            c_.fail("bad .npy header at " + c_.where(header_pos) + ": 'descr', 'fortran_order' and 'shape' are required");
        if (fortran->kind != PyValue::Kind::boolean) c_.fail("bad .npy header: 'fortran_order' is not True or False");
        if (shape->kind != PyValue::Kind::sequence) c_.fail("bad .npy header: 'shape' is not a tuple");
        NpyArray array;
        array.shape = read_shape(*shape);
        DType dtype;
        parse_dtype(*descr, dtype, 0);
        array.descr = dtype.text;
        const std::uint64_t elements = element_count(array.shape);
        std::uint64_t bytes = 0;
        if (!checked_mul(elements, dtype.size, bytes)) c_.fail("the shape " + shape_text(array.shape) + " is impossibly large");
        c_.require(bytes, "array data of shape " + shape_text(array.shape) + " and dtype " + quote(dtype.text));
        const unsigned char* data = c_.take(bytes, "array data");
        if (dtype.kind == DType::Kind::structured)
            add_field_columns(array, dtype, data, fortran->boolean);
        else
            add_plain_column(array, dtype, data, elements, fortran->boolean);
        return array;
    }


private:
    Cursor c_;
    std::uint64_t header_length_ = 0;

    // The magic and the version; returns where the header dictionary starts.
    std::size_t read_preamble() {
        if (c_.remaining() < 6 || std::memcmp(c_.here(), "\x93NUMPY", 6) != 0)
            c_.fail("not a NumPy .npy file: it does not start with '\\x93NUMPY'");
        c_.take(6, "magic");
        unsigned major = c_.u8("format version"), minor = c_.u8("format version");
        if (major == 1) {
            header_length_ = load_le16(c_.take(2, "header length"));
        } else if (major == 2 || major == 3) {
            header_length_ = load_le32(c_.take(4, "header length"));
        } else {
            c_.fail("unsupported .npy format version " + std::to_string(major) + "." + std::to_string(minor) +
                    " (supported: 1.0, 2.0, 3.0)");
        }
        // numpy itself refuses headers over 10000 bytes unless told otherwise; 1 MiB leaves room for huge records
        // and keeps the parsed literal small.
        if (header_length_ > (1u << 20)) c_.fail("the .npy header claims " + std::to_string(header_length_) + " bytes (more than 1 MiB)");
        return c_.pos();
    }

    PyValue read_header_dict(std::size_t header_pos) {
        const unsigned char* header = c_.take(header_length_, "the .npy header");
        std::string_view text(reinterpret_cast<const char*>(header), static_cast<std::size_t>(header_length_));
        PyValue dict = parse_python_literal(c_, text, header_pos, "bad .npy header");
        if (dict.kind != PyValue::Kind::dict) c_.fail("bad .npy header at " + c_.where(header_pos) + ": not a dictionary");
        return dict;
    }

    std::vector<std::uint64_t> read_shape(const PyValue& shape) {
        std::vector<std::uint64_t> out;
        for (const auto& dim : shape.items) {
            if (dim.kind != PyValue::Kind::integer || dim.integer < 0)
                c_.fail("bad .npy header: the shape has a dimension that is not a non-negative integer");
            out.push_back(static_cast<std::uint64_t>(dim.integer));
        }
        if (out.size() > 32) c_.fail("bad .npy header: " + std::to_string(out.size()) + " dimensions");
        return out;
    }

    std::uint64_t element_count(const std::vector<std::uint64_t>& shape) {
        std::uint64_t elements = 1;
        for (std::uint64_t dim : shape)
            if (!checked_mul(elements, dim, elements)) c_.fail("the shape " + shape_text(shape) + " is impossibly large");
        return elements;
    }

    // A structured array: one column per numeric field.
    void add_field_columns(NpyArray& array, const DType& dtype, const unsigned char* data, bool fortran) {
        array.structured = true;
        if (array.shape.size() != 1 || fortran) c_.fail("a structured array must have shape (N,), not " + shape_text(array.shape));
        const std::size_t n = static_cast<std::size_t>(array.shape[0]);
        for (const auto& f : dtype.fields) {
            if (!f.type->numeric()) continue;  // strings, nested records, padding: no float meaning
            // A zero-length subarray field ('velocity', '<f4', (0,)) holds no values. Skipped rather than refused:
            // numpy writes such dtypes for valid arrays, the other fields are intact and nothing is lost (an .npz
            // member of zero components is left out the same way); kept, it would be an attribute of 0
            // components, which no consumer can index. Readers have no warning channel, so the skip is silent.
            if (f.count == 0) continue;
            NpyColumn col;
            col.name = f.name;
            col.integral = f.type->kind == DType::Kind::number && scalar_is_integer(f.type->type);
            col.components = static_cast<int>(f.count);
            col.values.resize(n * f.count);
            for (std::uint64_t k = 0; k < f.count && n > 0; ++k)  // no pointer arithmetic on an empty vector's null data()
                convert(data + f.offset + k * f.type->size, n, static_cast<std::size_t>(dtype.size), *f.type,
                        col.values.data() + k, static_cast<std::size_t>(f.count));
            array.columns.push_back(std::move(col));
        }
    }

    // A plain numeric array: one column, rows of the product of the other dimensions.
    void add_plain_column(NpyArray& array, const DType& dtype, const unsigned char* data, std::uint64_t elements, bool fortran) {
        if (!dtype.numeric())
            c_.fail("unsupported dtype " + quote(dtype.text) + " (supported: bool, integers, float16/32/64, or a structured "
                    "array of them; object arrays are never unpickled)");
        NpyColumn col;
        col.integral = dtype.kind == DType::Kind::number && scalar_is_integer(dtype.type);
        // Values per row; 0 marks a row too wide to be a particle attribute (the array is then left out).
        std::uint64_t per_row = 1;
        for (std::size_t d = 1; d < array.shape.size(); ++d)
            if (!checked_mul(per_row, array.shape[d], per_row) || per_row > 65536) per_row = 65537;
        col.components = per_row > 65536 ? 0 : static_cast<int>(per_row);
        col.values.resize(static_cast<std::size_t>(elements));
        if (elements == 0) {
            // nothing to convert (and data() may be null)
        } else if (!fortran || array.shape.size() < 2) {
            convert(data, col.values.size(), static_cast<std::size_t>(dtype.size), dtype, col.values.data(), 1);
        } else {
            // Fortran order: the first index varies fastest. Only 2-D arrays occur in practice; general N-D
            // transposition would follow the same rule with more strides.
            if (array.shape.size() != 2) c_.fail("Fortran-ordered arrays with more than 2 dimensions are not supported");
            const std::size_t rows = static_cast<std::size_t>(array.shape[0]), cols = static_cast<std::size_t>(array.shape[1]);
            for (std::size_t k = 0; k < cols; ++k)
                convert(data + k * rows * dtype.size, rows, static_cast<std::size_t>(dtype.size), dtype, col.values.data() + k, cols);
        }
        array.columns.push_back(std::move(col));
    }

    void parse_simple_dtype(const std::string& text, DType& t) {
        t.text = text;
        std::size_t i = 0;
        char order = '=';
        if (!text.empty() && (text[0] == '<' || text[0] == '>' || text[0] == '|' || text[0] == '=')) order = text[i++];
        t.big_endian = order == '>';
        if (i >= text.size()) c_.fail("bad dtype " + quote(text));
        char kind = text[i++];
        if (kind == 'O') c_.fail("unsupported dtype " + quote(text) + ": object arrays are pickles, which are never loaded");
        std::uint64_t size = 0;
        std::string_view digits(text.data() + i, text.size() - i);
        std::size_t bracket = digits.find('[');  // datetime units: 'M8[ns]'
        if (bracket != std::string_view::npos) digits = digits.substr(0, bracket);
        if (kind == '?' && digits.empty()) size = 1;
        else if (!parse_u64(digits, size) || size == 0 || size > (1u << 20)) c_.fail("bad dtype " + quote(text));
        if (kind == 'U') {
            if (!checked_mul(size, 4, size)) c_.fail("bad dtype " + quote(text));
        }
        t.size = size;
        t.kind = DType::Kind::number;
        if ((kind == 'b' || kind == '?') && size == 1) t.type = ScalarType::u8;
        else if (kind == 'i' && size == 1) t.type = ScalarType::i8;
        else if (kind == 'i' && size == 2) t.type = ScalarType::i16;
        else if (kind == 'i' && size == 4) t.type = ScalarType::i32;
        else if (kind == 'i' && size == 8) t.type = ScalarType::i64;
        else if (kind == 'u' && size == 1) t.type = ScalarType::u8;
        else if (kind == 'u' && size == 2) t.type = ScalarType::u16;
        else if (kind == 'u' && size == 4) t.type = ScalarType::u32;
        else if (kind == 'u' && size == 8) t.type = ScalarType::u64;
        else if (kind == 'f' && size == 4) t.type = ScalarType::f32;
        else if (kind == 'f' && size == 8) t.type = ScalarType::f64;
        else if (kind == 'f' && size == 2) t.kind = DType::Kind::half;
        else t.kind = DType::Kind::skip;  // strings, void, complex, datetime, long double: skipped in records
    }

    void parse_dtype(const PyValue& v, DType& t, int depth) {
        if (depth > 8) c_.fail("bad .npy header: structured dtype nested too deeply");
        if (v.kind == PyValue::Kind::string) {
            parse_simple_dtype(v.string, t);
            return;
        }
        if (v.kind != PyValue::Kind::sequence) c_.fail("bad .npy header: 'descr' is neither a string nor a list of fields");
        t.kind = DType::Kind::structured;
        t.text = "structured";
        for (const auto& item : v.items) {
            if (item.kind != PyValue::Kind::sequence || item.items.size() < 2 || item.items.size() > 3)
                c_.fail("bad .npy header: a field of the structured dtype is not (name, type[, shape])");
            DType::Field field;
            const PyValue& name = item.items[0];
            if (name.kind == PyValue::Kind::string) field.name = name.string;
            else if (name.kind == PyValue::Kind::sequence && name.items.size() == 2 && name.items[1].kind == PyValue::Kind::string)
                field.name = name.items[1].string;  // (title, name)
            else c_.fail("bad .npy header: a field name is not a string");
            t.owned.push_back(std::make_unique<DType>());
            field.type = t.owned.back().get();
            parse_dtype(item.items[1], *field.type, depth + 1);
            if (item.items.size() == 3) {
                const PyValue& shape = item.items[2];
                std::vector<PyValue> dims = shape.kind == PyValue::Kind::sequence ? shape.items : std::vector<PyValue>{shape};
                for (const auto& d : dims) {
                    if (d.kind != PyValue::Kind::integer || d.integer < 0 || d.integer > 65536)
                        c_.fail("bad .npy header: field " + quote(field.name) + " has a bad subarray shape");
                    field.count *= static_cast<std::uint64_t>(d.integer);
                }
                if (field.count > 65536) c_.fail("bad .npy header: field " + quote(field.name) + " has more than 65536 components");
            }
            field.offset = t.size;
            std::uint64_t bytes = 0;
            if (!checked_mul(field.count, field.type->size, bytes) || t.size + bytes > (std::uint64_t(1) << 32))
                c_.fail("bad .npy header: the structured dtype is impossibly large");
            t.size += bytes;
            t.fields.push_back(std::move(field));
        }
        if (t.size == 0) c_.fail("bad .npy header: the structured dtype has no bytes");
    }
};

}  // namespace

NpyArray parse_npy(const Source& source) { return NpyParser(source).parse(); }

std::string shape_text(const std::vector<std::uint64_t>& shape) {
    std::string s = "(";
    for (std::size_t i = 0; i < shape.size(); ++i) s += (i ? ", " : "") + std::to_string(shape[i]);
    return s + (shape.size() == 1 ? ",)" : ")");
}

}  // namespace io_detail
}  // namespace meniscus
