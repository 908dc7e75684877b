// Houdini JSON geometry (Houdini 12 and later): ASCII .geo (plain JSON) and binary .bgeo (SideFX binary JSON,
// magic 0x7f "NSJb", or 0x7f "bJSN" when written big-endian), plain or gzip-compressed. The classic "BgeoV" layout is
// bgeo.cpp; the JSON itself is parsed by parsers/json.h.
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
// Not supported: the Blosc-compressed .sc variants (no Blosc decoder here) and the classic ASCII "PGEOMETRY" .geo.
// No Houdini-written JSON sample was available to the tests: the layouts follow the published binary JSON
// definitions and the geometry structure as other open readers decode it, and are tested on files written to them.
#include <algorithm>
#include <cmath>

#include "io/parsers/json.h"

namespace meniscus {
namespace io_detail {
namespace {

using Kind = JsonValue::Kind;

// The parts of the document the reader needs: the point count and the point attributes.
const JsonSelection& geometry_selection() {
    static const JsonSelection attributes = JsonSelection().keep("pointattributes");
    static const JsonSelection root = JsonSelection().keep("fileversion").keep("pointcount").keep("attributes", &attributes);
    return root;
}

// A tuple size or similar small count: 1 to 65536, else 0.
int small_int(const JsonValue* v) {
    if (!v || v->kind != Kind::number || !(v->number >= 1) || v->number > 65536 || v->number != std::floor(v->number)) return 0;
    return static_cast<int>(v->number);
}

// Whether a point attribute's values are stored as integers ("storage": "int32", "uint8", ...).
bool integer_storage(const JsonValue& body) {
    const JsonValue* values = json_lookup(body, "values");
    const JsonValue* storage = values ? json_lookup(*values, "storage") : nullptr;
    return storage && storage->kind == Kind::string && (storage->text.rfind("int", 0) == 0 || storage->text.rfind("uint", 0) == 0);
}

// The rawpagedata layout of one attribute: pages of `page` elements, each storing its packing groups one after the
// other, a group flagged constant in a page storing one tuple for all of the page's elements.
struct PageLayout {
    std::uint64_t page = 1, pages = 0;
    std::vector<std::size_t> packing;  // components per group, adding up to the tuple size
    const JsonValue* flags = nullptr;  // constantpageflags, one list per group (nullptr: no constant pages)

    bool constant(std::size_t group, std::uint64_t p) const {
        return flags && flags->row_size(group) > 0 && flags->cell(group, p) != 0;
    }
};

class Geometry {
public:
    Geometry(const Source& source, const JsonValue& root) : c_(source), root_(root), file_size_(source.size) {}

    ParticleData read() {
        read_point_count();
        const JsonValue* attributes = json_lookup(root_, "attributes");
        const JsonValue* points = attributes ? json_lookup(*attributes, "pointattributes") : nullptr;
        ParticleData out;
        bool have_p = false;
        if (points && points->kind == Kind::array)
            for (const JsonValue& entry : points->items) have_p = read_attribute(entry, out) || have_p;
        if (!have_p && n_ > 0) c_.fail("Houdini geometry with " + std::to_string(n_) + " points has no numeric point attribute P");
        return out;
    }

private:
    Cursor c_;
    const JsonValue& root_;
    std::size_t file_size_;
    std::uint64_t n_ = 0;

    void read_point_count() {
        const JsonValue* count = json_lookup(root_, "pointcount");
        if (!count || count->kind != Kind::number || !(count->number >= 0) || count->number > 1e15 ||
            count->number != std::floor(count->number))
            c_.fail("Houdini geometry without a valid \"pointcount\"");
        n_ = static_cast<std::uint64_t>(count->number);
    }

    // One [definition, body] entry of "pointattributes"; true when it was P (the positions).
    bool read_attribute(const JsonValue& entry, ParticleData& out) {
        if (entry.kind != Kind::array || entry.items.size() != 2) c_.fail("a point attribute is not a [definition, values] pair");
        const JsonValue* name = json_lookup(entry.items[0], "name");
        const JsonValue* type = json_lookup(entry.items[0], "type");
        if (!name || name->kind != Kind::string) c_.fail("a point attribute has no name");
        if (!type || type->kind != Kind::string || type->text != "numeric") return false;  // strings, indices
        int components = 0;
        std::vector<float> values = decode(name->text, entry.items[1], components);
        if (name->text == "P") {
            if (components < 3) c_.fail("the point attribute P has " + std::to_string(components) + " components, 3 needed");
            out.positions.resize(static_cast<std::size_t>(3 * n_));
            for (std::size_t i = 0; i < n_; ++i)
                for (int k = 0; k < 3; ++k) out.positions[3 * i + k] = values[i * static_cast<std::size_t>(components) + k];
            return true;
        }
        Attribute a;
        a.name = name->text;
        a.components = components;
        a.integral = integer_storage(entry.items[1]);
        a.values = std::move(values);
        out.attributes.push_back(std::move(a));
        return false;
    }

    // Every value must come from the file: refuse before allocating what the data cannot fill.
    std::vector<float> allocate(const std::string& what, std::uint64_t total, std::uint64_t available, std::size_t k) const {
        if (total > available)
            c_.fail(what + " holds " + std::to_string(available) + " values but " + std::to_string(n_) + " points of " +
                    std::to_string(k) + " components need " + std::to_string(total));
        return std::vector<float>(static_cast<std::size_t>(total));
    }

    std::vector<float> decode(const std::string& name, const JsonValue& body, int& components) {
        const std::string what = "point attribute " + quote(name);
        const JsonValue* values = json_lookup(body, "values");
        if (!values) c_.fail(what + " has no \"values\"");
        components = small_int(json_lookup(*values, "size"));
        if (!components) components = small_int(json_lookup(body, "size"));
        if (!components) c_.fail(what + " has no valid tuple size");
        const std::size_t k = static_cast<std::size_t>(components);
        std::uint64_t total = 0;
        if (!checked_mul(n_, k, total)) c_.fail(what + ": pointcount times tuple size is impossibly large");
        if (const JsonValue* tuples = json_lookup(*values, "tuples")) return from_tuples(what, *tuples, k, total);
        if (const JsonValue* arrays = json_lookup(*values, "arrays")) return from_arrays(what, *arrays, k, total);
        if (const JsonValue* raw = json_lookup(*values, "rawpagedata")) return from_pages(what, *values, *raw, k, total);
        c_.fail(what + ": unsupported value layout (expected tuples, arrays or rawpagedata)");
    }

    // "tuples": one numeric row per point (or, for one component, a flat numeric array).
    std::vector<float> from_tuples(const std::string& what, const JsonValue& tuples, std::size_t k, std::uint64_t total) {
        if (tuples.all_numeric() && tuples.kind != Kind::array) {
            if (k != 1 || tuples.size() != n_)
                c_.fail(what + " has " + std::to_string(tuples.size()) + " values as tuples for " + std::to_string(n_) +
                        " points of " + std::to_string(k) + " components");
            std::vector<float> out = allocate(what, total, n_, k);
            for (std::size_t i = 0; i < n_; ++i) out[i] = static_cast<float>(tuples.at(i));
            return out;
        }
        const std::uint64_t rows = tuples.rows();
        if (rows != n_) c_.fail(what + " has " + std::to_string(rows) + " numeric tuples for " + std::to_string(n_) + " points");
        // Every tuple is checked before the output is allocated: the tuple size alone must not decide it.
        for (std::uint64_t i = 0; i < n_; ++i)
            if (tuples.row_size(i) < k) c_.fail(what + ": tuple " + std::to_string(i) + " does not hold " + std::to_string(k) + " numbers");
        std::vector<float> out = allocate(what, total, total, k);
        for (std::uint64_t i = 0; i < n_; ++i)
            for (std::size_t j = 0; j < k; ++j) out[static_cast<std::size_t>(i * k + j)] = static_cast<float>(tuples.cell(i, j));
        return out;
    }

    // "arrays": one numeric array per component.
    std::vector<float> from_arrays(const std::string& what, const JsonValue& arrays, std::size_t k, std::uint64_t total) {
        if (arrays.rows() != k) c_.fail(what + ": \"arrays\" does not hold one numeric array per component");
        for (std::uint64_t j = 0; j < k; ++j)
            if (arrays.row_size(j) != n_) c_.fail(what + ": a component array does not hold " + std::to_string(n_) + " numbers");
        std::vector<float> out = allocate(what, total, total, k);
        for (std::size_t j = 0; j < k; ++j)
            for (std::uint64_t i = 0; i < n_; ++i) out[static_cast<std::size_t>(i * k + j)] = static_cast<float>(arrays.cell(j, i));
        return out;
    }

    // "rawpagedata": every value in page order, see PageLayout.
    std::vector<float> from_pages(const std::string& what, const JsonValue& values, const JsonValue& raw, std::size_t k,
                                  std::uint64_t total) {
        if (!raw.all_numeric()) c_.fail(what + ": rawpagedata is not numeric");
        PageLayout layout = page_layout(what, values, k);
        if (total > 0 && raw.size() == 0) c_.fail(what + ": rawpagedata is empty");
        layout.flags = constant_page_flags(what, values, layout);
        const std::uint64_t needed = page_values_needed(layout, total);
        if (needed != raw.size())
            c_.fail(what + ": rawpagedata holds " + std::to_string(raw.size()) + " values, the page layout needs " + std::to_string(needed));
        // Constant pages expand: cap the result like decompressed data, relative to the file.
        if (layout.flags && total > max_inflated_size(file_size_) / 4)
            c_.fail(what + ": constant pages expand to " + std::to_string(total) + " values, beyond what a file of " +
                    std::to_string(file_size_) + " bytes can describe; refusing a corrupt file");
        std::vector<float> out = allocate(what, total, layout.flags ? total : raw.size(), k);
        std::uint64_t src = 0;
        for (std::uint64_t p = 0; p < layout.pages; ++p) {
            const std::uint64_t first = p * layout.page, in_page = std::min(layout.page, n_ - first);
            std::size_t offset = 0;
            for (std::size_t g = 0; g < layout.packing.size(); ++g) {
                const std::size_t width = layout.packing[g];
                const bool constant = layout.constant(g, p);
                for (std::uint64_t e = 0; e < in_page; ++e) {
                    const std::uint64_t from = constant ? src : src + e * width;
                    for (std::size_t j = 0; j < width; ++j)
                        out[static_cast<std::size_t>((first + e) * k + offset + j)] = static_cast<float>(raw.at(from + j));
                }
                src += (constant ? 1 : in_page) * width;
                offset += width;
            }
        }
        return out;
    }

    // Page size and packing groups (the constant-page flags are read separately, after rawpagedata is checked).
    PageLayout page_layout(const std::string& what, const JsonValue& values, std::size_t k) {
        PageLayout layout;
        layout.page = n_ ? n_ : 1;
        if (const JsonValue* page = json_lookup(values, "pagesize")) {
            if (page->kind != Kind::number || !(page->number >= 1) || page->number > 1e9) c_.fail(what + ": bad pagesize");
            layout.page = static_cast<std::uint64_t>(page->number);
        }
        layout.pages = n_ / layout.page + (n_ % layout.page != 0);
        layout.packing = packing(what, values, k);
        return layout;
    }

    std::vector<std::size_t> packing(const std::string& what, const JsonValue& values, std::size_t k) {
        const JsonValue* p = json_lookup(values, "packing");
        if (!p) return {k};
        if (!p->all_numeric() || p->size() == 0 || p->size() > k) c_.fail(what + ": bad packing");
        std::vector<std::size_t> groups;
        std::size_t sum = 0;
        for (std::uint64_t i = 0; i < p->size(); ++i) {
            double g = p->at(i);
            if (!(g >= 1) || g > static_cast<double>(k)) c_.fail(what + ": bad packing");
            groups.push_back(static_cast<std::size_t>(g));
            sum += groups.back();
        }
        if (sum != k) c_.fail(what + ": packing adds up to " + std::to_string(sum) + ", not the tuple size " + std::to_string(k));
        return groups;
    }

    // Constant-page flags: one list per packing group, one flag per page; nullptr when there are none (no key, or
    // only empty lists).
    const JsonValue* constant_page_flags(const std::string& what, const JsonValue& values, const PageLayout& layout) {
        const JsonValue* flags = json_lookup(values, "constantpageflags");
        if (!flags) return nullptr;
        const std::size_t groups = layout.packing.size();
        bool empty_lists = flags->kind == Kind::array && flags->items.size() == groups;
        for (std::size_t g = 0; empty_lists && g < groups; ++g)
            empty_lists = flags->items[g].is_sequence() && flags->items[g].size() == 0;
        if (empty_lists) return nullptr;
        if (flags->rows() != groups) c_.fail(what + ": constantpageflags does not have one list per packing group");
        for (std::size_t g = 0; g < groups; ++g)
            if (flags->row_size(g) != 0 && flags->row_size(g) != layout.pages)
                c_.fail(what + ": constantpageflags has " + std::to_string(flags->row_size(g)) + " flags for " +
                        std::to_string(layout.pages) + " pages");
        return flags;
    }

    // How many values the layout stores, to check against what rawpagedata holds before anything is allocated.
    // Without constant pages that is simply every value; with them, the loop runs once per flag, and the flags are
    // in the file.
    std::uint64_t page_values_needed(const PageLayout& layout, std::uint64_t total) const {
        if (!layout.flags) return total;
        std::uint64_t needed = 0;
        for (std::uint64_t p = 0; p < layout.pages; ++p) {
            const std::uint64_t in_page = std::min(layout.page, n_ - p * layout.page);
            for (std::size_t g = 0; g < layout.packing.size(); ++g) needed += (layout.constant(g, p) ? 1 : in_page) * layout.packing[g];
        }
        return needed;
    }
};

}  // namespace

ParticleData read_houdini_json_particles(const Source& source) {
    const bool binary = source.size >= 1 && source.data[0] == kBinaryJsonMagic;
    JsonValue root = binary ? parse_binary_json(source, geometry_selection()) : parse_json_text(source, geometry_selection());
    return Geometry(source, root).read();
}

}  // namespace io_detail
}  // namespace meniscus
