// ASCII JSON. Strings keep their bytes (escapes decoded; \u escapes become '?', as the names that matter are
// ASCII); numbers are parsed as doubles.
#include <algorithm>

#include "io/parsers/json.h"

namespace meniscus {
namespace io_detail {
namespace {

class TextJsonParser {
public:
    explicit TextJsonParser(const Source& s) : c_(s), budget_(c_, s.size) {}

    JsonValue parse_document(const JsonSelection& selection) {
        JsonValue root;
        value(root, 0, &selection);
        c_.skip_space();
        if (!c_.at_end())
            c_.fail("unexpected " + quote(c_.view(c_.pos(), std::min(c_.size(), c_.pos() + 10))) + " after the JSON value at " + c_.where());
        return root;
    }

private:
    Cursor c_;
    JsonBudget budget_;

    [[noreturn]] void fail(const std::string& what) { c_.fail("bad JSON at " + c_.where() + ": " + what); }

    int peek() {
        c_.skip_space();
        return c_.at_end() ? -1 : *c_.here();
    }

    void expect(char ch) {
        if (peek() != ch) fail(std::string("expected '") + ch + "'" + (c_.at_end() ? " (truncated?)" : ""));
        c_.take(1, "JSON");
    }

    static bool starts_number(int ch) { return ch == '-' || (ch >= '0' && ch <= '9'); }

    bool word(std::string_view w) {
        if (c_.remaining() < w.size() || c_.view(c_.pos(), c_.pos() + w.size()) != w) return false;
        c_.take(w.size(), "JSON");
        return true;
    }

    // A string at the cursor; its text only when `keep` (skipped strings cost no memory).
    std::string string_value(bool keep) {
        expect('"');
        std::string out;
        while (true) {
            if (c_.at_end()) fail("a string is not closed (truncated?)");
            char ch = static_cast<char>(c_.u8("string"));
            if (ch == '"') return out;
            if (ch == '\\') ch = escaped_char();
            if (keep) out += ch;
        }
    }

    char escaped_char() {
        if (c_.at_end()) fail("a string is not closed (truncated?)");
        char e = static_cast<char>(c_.u8("escape"));
        switch (e) {
            case 'n': return '\n';
            case 't': return '\t';
            case 'r': return '\r';
            case 'b': return '\b';
            case 'f': return '\f';
            case 'u': c_.take(4, "\\u escape"); return '?';  // names are ASCII; keep the length honest
            default: return e;
        }
    }

    double number_value() {
        std::size_t start = c_.pos();
        while (!c_.at_end()) {
            char ch = static_cast<char>(*c_.here());
            if (!((ch >= '0' && ch <= '9') || ch == '-' || ch == '+' || ch == '.' || ch == 'e' || ch == 'E')) break;
            c_.take(1, "number");
        }
        double v = 0;
        std::string_view token = c_.view(start, c_.pos());
        if (!parse_double(token, v)) {
            c_.seek(start);
            fail("bad number " + quote(token));
        }
        return v;
    }

    void value(JsonValue& out, int depth, const JsonSelection* selection) {
        if (depth > kMaxJsonDepth) fail("nested more than " + std::to_string(kMaxJsonDepth) + " levels deep");
        const bool keep = selection != nullptr;
        int ch = peek();
        if (ch < 0) fail("a value is missing (truncated?)");
        if (ch == '"') {
            out.kind = JsonValue::Kind::string;
            out.text = string_value(keep);
            if (keep) budget_.take(out.text.size());
        } else if (ch == '[' || ch == '{') {
            container(out, ch == '{', depth, selection);
        } else if (ch == 't' && word("true")) {
            out.kind = JsonValue::Kind::boolean;
            out.number = 1;
        } else if (ch == 'f' && word("false")) {
            out.kind = JsonValue::Kind::boolean;
        } else if (ch == 'n' && word("null")) {
            out.kind = JsonValue::Kind::null;
        } else if (starts_number(ch)) {
            out.kind = JsonValue::Kind::number;
            out.number = number_value();
        } else {
            fail("unexpected character " + quote(std::string(1, static_cast<char>(ch))));
        }
    }

    void container(JsonValue& out, bool is_map, int depth, const JsonSelection* selection) {
        c_.take(1, "JSON");
        JsonContainerBuilder builder(out, is_map, selection, budget_);
        for (bool first = true;; first = false) {
            if (peek() == (is_map ? '}' : ']')) {
                c_.take(1, "JSON");
                break;
            }
            if (!first) expect(',');
            std::string key;
            if (is_map) {
                key = string_value(true);
                expect(':');
            }
            if (!is_map && starts_number(peek())) {  // the common case: no node at all
                builder.add_number(number_value());
                continue;
            }
            JsonValue item;
            value(item, depth + 1, builder.child_selection(key));
            builder.add(std::move(key), std::move(item));
        }
        builder.finish();
    }
};

}  // namespace

JsonValue parse_json_text(const Source& source, const JsonSelection& selection) {
    return TextJsonParser(source).parse_document(selection);
}

}  // namespace io_detail
}  // namespace meniscus
