// JSON documents as Houdini writes its geometry: ASCII JSON (RFC 8259) and SideFX's binary JSON (UT_JSONDefines.h),
// both parsed into the same JsonValue tree by one container builder.
//
// Memory: a parser builds values only for the parts of the document a JsonSelection asks for (everything else is
// parsed only to be skipped), packs numeric arrays (8 bytes a number instead of a node each; binary uniform arrays
// stay views of the file) and charges what it builds against a budget relative to the file size, so that a file of
// nested empty arrays or one-number tuples cannot turn into gigabytes of nodes.
//
// Maps may also be written as flat arrays [key, value, key, value, ...] (Houdini does): in an array, a string item
// is taken as the key of the item after it when selecting what to build, and json_lookup finds keys either way.
#pragma once
#include <cstdint>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "io/io_util.h"

namespace meniscus {
namespace io_detail {

constexpr int kMaxJsonDepth = 64;  // nesting; Houdini geometry uses about 8 levels

// One JSON value. Numeric arrays are packed: ASCII ones into `numbers`, binary uniform arrays as a view of the file.
struct JsonValue {
    // numbers: a packed array of plain numbers; matrix: packed equal-length numeric rows (tuples), `width` each;
    // uniform: a binary array of `count` values of `type` at `data`; bits: `count` packed booleans at `data`.
    enum class Kind : std::uint8_t { null, boolean, number, string, array, map, numbers, matrix, uniform, bits } kind = Kind::null;
    double number = 0.0;                                   // number, boolean (0 or 1)
    std::string text;                                      // string
    std::vector<JsonValue> items;                          // array (and map values, with keys in `keys`)
    std::vector<std::string> keys;                         // map keys
    std::vector<double> numbers;                           // packed numbers or matrix rows
    std::uint64_t width = 0;                               // matrix row length
    const unsigned char* data = nullptr;                   // uniform binary array or bits
    ScalarType type = ScalarType::f32;
    bool big_endian = false;
    std::uint64_t count = 0;

    bool is_sequence() const { return kind == Kind::array || kind == Kind::numbers || kind == Kind::uniform || kind == Kind::bits; }
    // Elements of a sequence (a matrix counts its rows; see rows()).
    std::uint64_t size() const;
    // A short numeric sequence, packed into a matrix row when it comes in a run of equal-length ones.
    bool is_row() const { return (kind == Kind::numbers || kind == Kind::uniform) && size() >= 1 && size() <= 64; }
    // Element i of a numeric sequence as a double (NaN when it is not a number).
    double at(std::uint64_t i) const;
    // A 2-D numeric table: a packed matrix, or an array whose items are numeric sequences. rows() is 0 when the value
    // is neither; row_size(i) is the length of row i; cell(i, j) an element.
    std::uint64_t rows() const;
    std::uint64_t row_size(std::uint64_t i) const;
    double cell(std::uint64_t i, std::uint64_t j) const;
    bool all_numeric() const;
};

// The value under `key` in a map, or in a flat [key, value, ...] array; nullptr when absent.
const JsonValue* json_lookup(const JsonValue& v, std::string_view key);

// Which parts of a document to build, by key: a tree of wanted keys below the root. Values under keys that are not
// wanted are skipped; below a key selected with everything(), all is built. Items of arrays without keys are built
// as their container is.
class JsonSelection {
public:
    static const JsonSelection* everything();

    // Builds the value under `key`, with `below` deciding what of it.
    JsonSelection& keep(std::string key, const JsonSelection* below = everything());
    // What to build of a child of a value selected by `level` (nullptr: nothing); `keyed` says whether the child has
    // a key (a map entry, or an array item after its key string).
    static const JsonSelection* child(const JsonSelection* level, bool keyed, std::string_view key);

private:
    std::vector<std::pair<std::string, const JsonSelection*>> keys_;
};

// What a parser may still build, in bytes; exceeding it is a FormatError.
class JsonBudget {
public:
    JsonBudget(const Cursor& c, std::size_t file_size) : c_(c), left_(16 * std::uint64_t(file_size) + (std::uint64_t(64) << 20)) {}
    void take(std::uint64_t bytes);

private:
    const Cursor& c_;
    std::uint64_t left_;
};

// Builds one array or map as a parser reads its children: keeps track of keys (also in flat [key, value] arrays),
// says what to build of each child, and packs runs of numbers and of equal-length numeric rows. Shared by the ASCII
// and the binary parser, so that both give the same tree for the same document.
class JsonContainerBuilder {
public:
    JsonContainerBuilder(JsonValue& out, bool is_map, const JsonSelection* level, JsonBudget& budget)
        : out_(out), is_map_(is_map), level_(level), budget_(budget) {
        out.kind = is_map ? JsonValue::Kind::map : JsonValue::Kind::array;
    }

    // What to build of the next child; `key` is its map key (ignored in arrays).
    const JsonSelection* child_selection(std::string_view key) const;
    // The next child, parsed with child_selection(key).
    void add(std::string&& key, JsonValue&& item);
    // A number in an array, parsed straight from text (no node is made for it).
    void add_number(double v);
    // Ends the container: packed arrays get their kind.
    void finish();

private:
    JsonValue& out_;
    bool is_map_;
    const JsonSelection* level_;  // nullptr: the container is skipped, nothing is built
    JsonBudget& budget_;
    std::string pending_key_;  // flat [key, value] arrays: the key just read
    bool after_key_ = false;
    // How the array items are stored so far: packed numbers, packed rows, or nodes.
    enum class Packing { empty, scalars, rows, nodes } packing_ = Packing::empty;

    void append(JsonValue&& item);
    void unpack();
};

// Parses a source that holds one ASCII JSON value (white space around it allowed).
JsonValue parse_json_text(const Source& source, const JsonSelection& selection);

// SideFX binary JSON: 0x7f, then "NSJb" (little-endian) or "bJSN" (big-endian), then one value; trailing bytes (an
// index some Houdini versions append) are ignored.
constexpr unsigned char kBinaryJsonMagic = 0x7f;
JsonValue parse_binary_json(const Source& source, const JsonSelection& selection);

}  // namespace io_detail
}  // namespace meniscus
