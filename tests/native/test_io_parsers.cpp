// Unit tests of the general parsers the readers share (native/core/io/parsers/): half floats, base64, the XML
// scanner, ASCII and binary JSON, Python literals and zip archives, each on bytes in memory.
#include <zlib.h>

#include <catch2/catch.hpp>
#include <cmath>
#include <cstring>
#include <string>
#include <vector>

#include "io/io_util.h"
#include "io/parsers/base64.h"
#include "io/parsers/half_float.h"
#include "io/parsers/json.h"
#include "io/parsers/python_literal.h"
#include "io/parsers/xml.h"
#include "io/parsers/zip.h"
#include "reader_checks.h"

using namespace meniscus;
using namespace meniscus::io_detail;

namespace {

// A source over a string that outlives it (the parsers keep pointers into it).
struct TextSource {
    std::string text;
    Source source;
    explicit TextSource(std::string t, const std::string& path = "mem.bin")
        : text(std::move(t)), source{path, reinterpret_cast<const unsigned char*>(text.data()), text.size(), false} {}
};

std::string decode_base64(const std::string& text, std::size_t n) {
    TextSource s(text);
    Cursor c(s.source);
    Base64Reader reader(c, {{0, text.size()}}, "the test data");
    std::string out(n, '\0');
    reader.read(reinterpret_cast<unsigned char*>(&out[0]), n);
    return out;
}

// Records what the XML scanner reports, one line per event.
struct Recorder : XmlVisitor {
    const Cursor& c;
    std::vector<std::string> events;
    std::string stop_at;
    explicit Recorder(const Cursor& cursor) : c(cursor) {}
    bool start_element(const XmlTag& tag, const std::vector<std::string_view>& open, std::size_t) override {
        std::string e = "start " + std::string(tag.name) + " depth " + std::to_string(open.size());
        for (const auto& a : tag.attributes) e += " " + std::string(a.first) + "=" + std::string(a.second);
        if (tag.self_closing) e += " empty";
        events.push_back(e);
        return tag.name != stop_at;
    }
    void end_element(std::string_view name, std::size_t depth) override {
        events.push_back("end " + std::string(name) + " depth " + std::to_string(depth));
    }
    void text(TextRange range, std::size_t depth) override {
        std::string_view t = c.view(range.begin, range.end);
        if (t.find_first_not_of(" \n") != std::string_view::npos) events.push_back("text '" + std::string(t) + "' depth " + std::to_string(depth));
    }
};

std::vector<std::string> scan(const std::string& xml, const std::string& stop_at = "") {
    TextSource s(xml);
    Cursor c(s.source);
    Recorder r(c);
    r.stop_at = stop_at;
    scan_xml(c, r, 8);
    return r.events;
}

JsonValue text_json(const std::string& text, const JsonSelection& selection = *JsonSelection::everything()) {
    TextSource s(text);
    return parse_json_text(s.source, selection);
}

PyValue python_literal(const std::string& text) {
    TextSource s(text);
    Cursor c(s.source);
    return parse_python_literal(c, s.text, 0, "bad literal");
}

void put_le16(Bytes& b, unsigned v) {
    b.push_back(static_cast<unsigned char>(v));
    b.push_back(static_cast<unsigned char>(v >> 8));
}
void put_le32(Bytes& b, std::uint32_t v) {
    put_le16(b, v & 0xffff);
    put_le16(b, v >> 16);
}

// A zip of one member, stored (method 0) or deflated (method 8), with the given flags.
Bytes one_member_zip(const std::string& name, const Bytes& data, int method, unsigned flags = 0) {
    const Bytes payload = method == 8 ? test::deflate_bytes(data, -15) : data;
    const std::uint32_t crc = static_cast<std::uint32_t>(crc32(0, data.data(), static_cast<uInt>(data.size())));
    Bytes out;
    auto header = [&](bool central) {
        put_le32(out, central ? 0x02014b50u : 0x04034b50u);
        if (central) put_le16(out, 20);
        put_le16(out, 20);
        put_le16(out, flags);
        put_le16(out, static_cast<unsigned>(method));
        put_le32(out, 0);  // time and date
        put_le32(out, crc);
        put_le32(out, static_cast<std::uint32_t>(payload.size()));
        put_le32(out, static_cast<std::uint32_t>(data.size()));
        put_le16(out, static_cast<unsigned>(name.size()));
        put_le16(out, 0);
        if (central) {
            for (int k = 0; k < 3; ++k) put_le16(out, 0);  // comment length, disk, internal attributes
            put_le32(out, 0);                              // external attributes
            put_le32(out, 0);                              // local header offset
        }
        out.insert(out.end(), name.begin(), name.end());
    };
    header(false);
    out.insert(out.end(), payload.begin(), payload.end());
    const std::size_t directory = out.size();
    header(true);
    const std::size_t directory_size = out.size() - directory;
    put_le32(out, 0x06054b50u);
    put_le32(out, 0);
    put_le16(out, 1);
    put_le16(out, 1);
    put_le32(out, static_cast<std::uint32_t>(directory_size));
    put_le32(out, static_cast<std::uint32_t>(directory));
    put_le16(out, 0);
    return out;
}

}  // namespace

TEST_CASE("half floats decode exactly, every bit pattern", "[io][parsers]") {
    std::size_t wrong = 0;
    for (std::uint32_t h = 0; h < 65536; ++h) {
        const float f = half_to_float(static_cast<std::uint16_t>(h));
        const int exponent = (h >> 10) & 31, mantissa = h & 1023;
        const float sign = h & 0x8000 ? -1.0f : 1.0f;
        if (exponent == 31) {
            std::uint32_t bits;
            std::memcpy(&bits, &f, 4);
            wrong += mantissa ? !(std::isnan(f) && ((bits >> 13) & 1023) == static_cast<std::uint32_t>(mantissa)) : f != sign * INFINITY;
            continue;
        }
        const float expected = exponent ? sign * std::ldexp(float(mantissa + 1024), exponent - 25) : sign * std::ldexp(float(mantissa), -24);
        wrong += f != expected || std::signbit(f) != std::signbit(sign);
    }
    REQUIRE(wrong == 0);
    CHECK(half_to_float(0x3c00) == 1.0f);
    CHECK(half_to_float(0xc000) == -2.0f);
    CHECK(half_to_float(0x0001) == std::ldexp(1.0f, -24));  // the smallest subnormal
    CHECK(half_to_float(0x7bff) == 65504.0f);               // the largest normal
}

TEST_CASE("base64 decodes across white space, ranges and mid-string padding", "[io][parsers]") {
    CHECK(decode_base64("TWFu", 3) == "Man");
    CHECK(decode_base64(" TW\nFu\tTWE= ", 5) == "ManMa");
    CHECK(decode_base64("TQ==TWE=", 3) == "MMa");  // VTK writes a header and its data as two strings

    // Several text ranges are one stream.
    TextSource s("TW<x/>Fu");
    Cursor c(s.source);
    Base64Reader split(c, {{0, 2}, {6, 8}}, "split data");
    CHECK(split.max_remaining() >= 3);
    unsigned char out[3];
    split.read(out, 3);
    CHECK(std::string(reinterpret_cast<char*>(out), 3) == "Man");

    CHECK_THAT(test::format_error_of([] { decode_base64("TW*u", 3); }), Catch::StartsWith("mem.bin: invalid base64 character '*' at byte 2 in the test data"));
    CHECK_THAT(test::format_error_of([] { decode_base64("TWFu", 4); }), Catch::Contains("truncated base64 data in the test data: it ends after 3 bytes"));
    CHECK_THAT(test::format_error_of([] { decode_base64("TWFuT", 4); }), Catch::Contains("a lone character at byte 4"));
    CHECK_THAT(test::format_error_of([] { decode_base64("=TWF", 1); }), Catch::Contains("bad base64 padding at byte 0"));
    CHECK_THAT(test::format_error_of([] { decode_base64("TQ=x", 1); }), Catch::Contains("bad base64 padding at byte 3"));
}

TEST_CASE("the XML scanner reports tags, text and nesting", "[io][parsers]") {
    const auto events = scan("\xef\xbb\xbf<?xml version=\"1.0\"?>\n<!DOCTYPE x>\n<a k='1' m=\"two words\">\n<!-- <b> ignored -->"
                             "<b/>text<c><![CDATA[<raw>]]></c></a>");
    const std::vector<std::string> expected = {
        "start a depth 0 k=1 m=two words", "start b depth 1 empty", "text 'text' depth 1", "start c depth 1",
        "text '<raw>' depth 2", "end c depth 1", "end a depth 0"};
    CHECK(events == expected);
    // The visitor can end the scan: what follows is not markup.
    CHECK(scan("<a><data/>\x01\x02<<<", "data") == std::vector<std::string>{"start a depth 0", "start data depth 1 empty"});

    auto error = [](const std::string& xml) { return test::format_error_of([&] { scan(xml); }); };
    CHECK_THAT(error("<a></b>"), Catch::Contains("closing tag </b> does not match <a> at byte 3"));
    CHECK_THAT(error("<a><b>"), Catch::Contains("truncated at byte 6: the XML element <b> is not closed"));
    CHECK_THAT(error("<a><!-- x"), Catch::Contains("the XML comment started at byte 3 is not closed"));
    CHECK_THAT(error("<a k></a>"), Catch::Contains("attribute 'k' without a value"));
    CHECK_THAT(error("<a k=v></a>"), Catch::Contains("attribute 'k' without a quoted value"));
    CHECK_THAT(error("<a k='v></a>"), Catch::Contains("the value of attribute 'k' is not closed"));
    CHECK_THAT(error("< a/>"), Catch::Contains("malformed XML tag at byte 0"));
    CHECK_THAT(error("<a><a><a><a><a><a><a><a><a>"), Catch::Contains("XML nested more than 8 levels deep"));

    CHECK(decode_xml_entities("a &lt;&gt;&amp;&quot;&apos; &#65;&#x41; &unknown; &") == "a <>&\"' A&#x41; &unknown; &");
}

TEST_CASE("ASCII JSON: values, packing, selections and errors", "[io][parsers]") {
    JsonValue v = text_json(" {\"n\": [1, 2.5, -3e2], \"rows\": [[1, 2], [3, 4]], \"s\": \"a\\\"b\\n\\u00e9\", \"t\": true, \"z\": null,"
                            " \"flat\": [\"k\", 7, \"mixed\", [1, \"x\"]]} ");
    REQUIRE(v.kind == JsonValue::Kind::map);
    const JsonValue* n = json_lookup(v, "n");
    REQUIRE(n);
    CHECK(n->kind == JsonValue::Kind::numbers);  // packed, no node per number
    CHECK(n->size() == 3);
    CHECK(n->at(2) == -300.0);
    const JsonValue* rows = json_lookup(v, "rows");
    REQUIRE(rows);
    CHECK(rows->kind == JsonValue::Kind::matrix);
    CHECK(rows->rows() == 2);
    CHECK(rows->cell(1, 0) == 3.0);
    CHECK(json_lookup(v, "s")->text == "a\"b\n?");
    CHECK(json_lookup(v, "t")->number == 1.0);
    CHECK(json_lookup(v, "z")->kind == JsonValue::Kind::null);
    const JsonValue* flat = json_lookup(v, "flat");
    REQUIRE(flat);
    CHECK(json_lookup(*flat, "k")->number == 7.0);  // flat [key, value] arrays look up like maps
    CHECK(json_lookup(*flat, "mixed")->items.size() == 2);
    CHECK(!json_lookup(v, "missing"));

    // Only the selected keys are built; what is skipped is still parsed (and must be valid).
    JsonSelection inner;
    inner.keep("b");
    JsonSelection root;
    root.keep("keep").keep("nested", &inner);
    JsonValue s = text_json("[\"keep\", [1, 2], \"drop\", [3, 4], \"nested\", [\"a\", \"x\", \"b\", \"y\"]]", root);
    CHECK(json_lookup(s, "keep")->size() == 2);
    CHECK(json_lookup(s, "drop")->size() == 0);
    const JsonValue* nested = json_lookup(s, "nested");
    REQUIRE(nested);
    CHECK(json_lookup(*nested, "a")->text.empty());
    CHECK(json_lookup(*nested, "b")->text == "y");

    auto error = [](const std::string& text) { return test::format_error_of([&] { text_json(text); }); };
    CHECK_THAT(error("[1, 2] x"), Catch::Contains("unexpected 'x' after the JSON value at byte 7"));
    CHECK_THAT(error("[1, 2"), Catch::Contains("bad JSON at byte 5: expected ','"));
    CHECK_THAT(error("[1-2]"), Catch::Contains("bad number '1-2'"));
    CHECK_THAT(error("[\"abc"), Catch::Contains("a string is not closed"));
    CHECK_THAT(error(std::string(100, '[')), Catch::Contains("nested more than 64 levels deep"));
}

TEST_CASE("binary JSON: tokens, uniform arrays and both byte orders give the ASCII tree", "[io][parsers]") {
    for (bool big : {false, true}) {
        INFO((big ? "big-endian" : "little-endian"));
        Bytes b = {0x7f};
        const char* magic = big ? "bJSN" : "NSJb";
        b.insert(b.end(), magic, magic + 4);
        auto u16 = [&](unsigned v) {
            if (big) b.insert(b.end(), {static_cast<unsigned char>(v >> 8), static_cast<unsigned char>(v)});
            else b.insert(b.end(), {static_cast<unsigned char>(v), static_cast<unsigned char>(v >> 8)});
        };
        auto f32 = [&](float f) {
            std::uint32_t u;
            std::memcpy(&u, &f, 4);
            if (big) u16(u >> 16), u16(u & 0xffff);
            else u16(u & 0xffff), u16(u >> 16);
        };
        auto string = [&](const std::string& s) {
            b.push_back(0x27);
            b.push_back(static_cast<unsigned char>(s.size()));
            b.insert(b.end(), s.begin(), s.end());
        };
        b.push_back(0x5b);                       // [
        b.insert(b.end(), {0x2b, 5, 4, 'p', 'o', 's', 'n'});  // token 5 = "posn"
        b.insert(b.end(), {0x26, 5});            // "posn"
        b.insert(b.end(), {0x40, 0x19, 3});      // uniform float32 array of 3
        for (float f : {1.5f, -2.0f, 4.0f}) f32(f);
        string("half");
        b.insert(b.end(), {0x18});               // real16
        u16(0x3c00);
        string("map");
        b.push_back(0x7b);                       // {
        string("k");
        b.insert(b.end(), {0x11, 0xff});         // int8 -1
        b.push_back(0x7d);                       // }
        string("bits");
        b.insert(b.end(), {0x40, 0x10, 3});      // 3 packed booleans in one word: 0b101
        if (big) b.insert(b.end(), {0, 0, 0, 5});
        else b.insert(b.end(), {5, 0, 0, 0});
        b.push_back(0x5d);                       // ]
        Source source{"mem.bgeo", b.data(), b.size(), false};
        JsonValue v = parse_binary_json(source, *JsonSelection::everything());
        const JsonValue* posn = json_lookup(v, "posn");
        REQUIRE(posn);
        CHECK(posn->kind == JsonValue::Kind::uniform);  // a view of the file, not a copy
        CHECK(posn->at(0) == 1.5);
        CHECK(posn->at(2) == 4.0);
        CHECK(json_lookup(v, "half")->number == 1.0);
        CHECK(json_lookup(*json_lookup(v, "map"), "k")->number == -1.0);
        const JsonValue* bits = json_lookup(v, "bits");
        CHECK((bits->at(0) == 1 && bits->at(1) == 0 && bits->at(2) == 1));
    }
    auto error = [](Bytes b) {
        Source source{"mem.bgeo", b.data(), b.size(), false};
        return test::format_error_of([&] { parse_binary_json(source, *JsonSelection::everything()); });
    };
    CHECK_THAT(error({0x7f, 'N', 'S', 'J', 'x', 0x5b}), Catch::Contains("bad magic number"));
    CHECK_THAT(error({0x7f, 'N', 'S', 'J', 'b', 0x26, 9}), Catch::Contains("reference to undefined string token 9 at byte 5"));
    CHECK_THAT(error({0x7f, 'N', 'S', 'J', 'b', 0x99}), Catch::Contains("unknown binary JSON token 153 at byte 5"));
    CHECK_THAT(error({0x7f, 'N', 'S', 'J', 'b', 0x40, 0x19, 0xf4, 0xff, 0xff, 0xff, 0x7f}), Catch::Contains("uniform array of 2147483647 values"));
}

TEST_CASE("Python literals as the .npy header writes them", "[io][parsers]") {
    PyValue v = python_literal("{'descr': [('x', '<f4'), (('title', 'y'), '>f8', (3,))], \"fortran_order\": False, 'shape': (10L, 3), "
                               "'flag': True, 'none': None, 'neg': -5, 'esc': 'a\\'b', }");
    REQUIRE(v.kind == PyValue::Kind::dict);
    const PyValue* descr = v.get("descr");
    REQUIRE(descr);
    REQUIRE(descr->items.size() == 2);
    CHECK(descr->items[1].items[0].items[1].string == "y");
    CHECK(descr->items[1].items[2].items[0].integer == 3);
    CHECK(v.get("fortran_order")->kind == PyValue::Kind::boolean);
    CHECK(!v.get("fortran_order")->boolean);
    CHECK(v.get("shape")->items[0].integer == 10);
    CHECK(v.get("flag")->boolean);
    CHECK(v.get("none")->kind == PyValue::Kind::none);
    CHECK(v.get("neg")->integer == -5);
    CHECK(v.get("esc")->string == "a'b");
    CHECK(!v.get("missing"));

    auto error = [](const std::string& text) { return test::format_error_of([&] { python_literal(text); }); };
    CHECK_THAT(error("{'a': 'b"), Catch::StartsWith("mem.bin: bad literal at byte 8: a string is not closed"));
    CHECK_THAT(error("{'a' 1}"), Catch::Contains("expected ':' after key 'a'"));
    CHECK_THAT(error("{1: 2}"), Catch::Contains("a dictionary key is not a string"));
    CHECK_THAT(error("(1 2)"), Catch::Contains("expected ',' or ')'"));
    CHECK_THAT(error("{} x"), Catch::Contains("unexpected 'x'"));
    CHECK_THAT(error("99999999999999999999"), Catch::Contains("bad integer"));
    CHECK_THAT(error(std::string(20, '[')), Catch::Contains("nested too deeply"));
    CHECK_THAT(error("os.system"), Catch::Contains("unexpected 'os.system'"));  // nothing is evaluated
}

TEST_CASE("zip archives: stored and deflated members, CRC, refusals", "[io][parsers]") {
    Bytes data;
    for (int i = 0; i < 5000; ++i) data.push_back(static_cast<unsigned char>(i % 7));
    for (int method : {0, 8}) {
        INFO("method " << method);
        Bytes zip = one_member_zip("member.npy", data, method);
        Source source{"mem.npz", zip.data(), zip.size(), false};
        ZipReader reader(source);
        auto members = reader.members();
        REQUIRE(members.size() == 1);
        CHECK(members[0].name == "member.npy");
        CHECK(members[0].uncompressed == data.size());
        std::uint64_t budget = 1 << 20;
        CHECK(reader.extract(members[0], budget) == data);
        CHECK(budget == (method == 8 ? (1u << 20) - data.size() : 1u << 20));  // only inflating counts

        Bytes corrupt = zip;
        corrupt[30 + 10 + 5] ^= 1;  // a byte of the member's data
        Source damaged{"mem.npz", corrupt.data(), corrupt.size(), false};
        ZipReader damaged_reader(damaged);
        auto damaged_members = damaged_reader.members();
        CHECK(!test::format_error_of([&] { damaged_reader.extract(damaged_members[0], budget); }).empty());
    }
    auto error = [](const Bytes& zip) {
        Source source{"mem.npz", zip.data(), zip.size(), false};
        return test::format_error_of([&] {
            ZipReader reader(source);
            std::uint64_t budget = 1 << 20;
            for (const auto& m : reader.members()) reader.extract(m, budget);
        });
    };
    Bytes stored = one_member_zip("a.npy", data, 0);
    Bytes bad_crc = stored;
    bad_crc[30 + 5 + 7] ^= 1;
    CHECK_THAT(error(bad_crc), Catch::Contains("zip member 'a.npy': CRC-32 mismatch"));
    CHECK_THAT(error(one_member_zip("a.npy", data, 0, 1)), Catch::Contains("is encrypted"));
    CHECK_THAT(error(one_member_zip("a.npy", data, 12)), Catch::Contains("compression method 12 (bzip2)"));
    CHECK_THAT(error(Bytes(stored.begin(), stored.end() - 30)), Catch::Contains("no zip end-of-central-directory record"));
    CHECK_THAT(error(Bytes(10, 0)), Catch::Contains("bytes are too few for the end record"));
}
