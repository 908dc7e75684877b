#include "io/parsers/python_literal.h"

namespace meniscus {
namespace io_detail {

const PyValue* PyValue::get(std::string_view key) const {
    for (const auto& e : entries)
        if (e.first == key) return &e.second;
    return nullptr;
}

namespace {

constexpr int kMaxDepth = 16;  // .npy headers nest 3 levels (dict, field list, field tuple) plus nested records

class PyLiteralParser {
public:
    PyLiteralParser(const Cursor& c, std::string_view text, std::size_t base, const std::string& context)
        : c_(c), text_(text), base_(base), context_(context) {}

    PyValue parse() {
        PyValue v = value(0);
        skip_space();
        if (pos_ < text_.size()) fail("unexpected " + quote(text_.substr(pos_, 10)) + " after the header dictionary");
        return v;
    }

private:
    const Cursor& c_;
    std::string_view text_;
    std::size_t base_;  // file offset of text_[0], for messages
    const std::string& context_;
    std::size_t pos_ = 0;

    [[noreturn]] void fail(const std::string& what) const { c_.fail(context_ + " at " + c_.where(base_ + pos_) + ": " + what); }

    void skip_space() {
        while (pos_ < text_.size() && Cursor::is_space(static_cast<unsigned char>(text_[pos_]))) ++pos_;
    }

    bool word(std::string_view w) {
        if (text_.substr(pos_, w.size()) != w) return false;
        pos_ += w.size();
        return true;
    }

    // After an item: past a ',', or at `close` (left for at_close); anything else is an error.
    void end_of_item(char close, const std::string& expected) {
        skip_space();
        if (pos_ < text_.size() && text_[pos_] == ',')
            ++pos_;
        else if (pos_ >= text_.size() || text_[pos_] != close)
            fail(expected);
    }

    // True (and consumed) when the next character is `close`.
    bool at_close(char close) {
        skip_space();
        if (pos_ < text_.size() && text_[pos_] == close) {
            ++pos_;
            return true;
        }
        return false;
    }

    PyValue value(int depth) {
        if (depth > kMaxDepth) fail("nested too deeply");
        skip_space();
        if (pos_ >= text_.size()) fail("it ends in the middle of a value");
        const char ch = text_[pos_];
        if (ch == '{') return dict(depth);
        if (ch == '(' || ch == '[') return sequence(depth, ch == '(' ? ')' : ']');
        if (ch == '\'' || ch == '"') return string(ch);
        if (ch == '-' || ch == '+' || (ch >= '0' && ch <= '9')) return integer();
        PyValue v;
        if (word("True")) {
            v.kind = PyValue::Kind::boolean;
            v.boolean = true;
        } else if (word("False")) {
            v.kind = PyValue::Kind::boolean;
        } else if (!word("None")) {
            fail("unexpected " + quote(text_.substr(pos_, 10)));
        }
        return v;
    }

    PyValue dict(int depth) {
        PyValue v;
        v.kind = PyValue::Kind::dict;
        ++pos_;
        while (!at_close('}')) {
            PyValue key = value(depth + 1);
            if (key.kind != PyValue::Kind::string) fail("a dictionary key is not a string");
            skip_space();
            if (pos_ >= text_.size() || text_[pos_] != ':') fail("expected ':' after key " + quote(key.string));
            ++pos_;
            v.entries.emplace_back(key.string, value(depth + 1));
            end_of_item('}', "expected ',' or '}' in the dictionary");
        }
        return v;
    }

    PyValue sequence(int depth, char close) {
        PyValue v;
        v.kind = PyValue::Kind::sequence;
        ++pos_;
        while (!at_close(close)) {
            v.items.push_back(value(depth + 1));
            end_of_item(close, std::string("expected ',' or '") + close + "'");
        }
        return v;
    }

    // A quoted string; a backslash keeps the character after it as it is.
    PyValue string(char quote_char) {
        PyValue v;
        v.kind = PyValue::Kind::string;
        ++pos_;
        while (pos_ < text_.size() && text_[pos_] != quote_char) {
            if (text_[pos_] == '\\' && pos_ + 1 < text_.size()) ++pos_;
            v.string += text_[pos_++];
        }
        if (pos_ >= text_.size()) fail("a string is not closed");
        ++pos_;
        return v;
    }

    PyValue integer() {
        PyValue v;
        std::size_t start = pos_;
        ++pos_;
        while (pos_ < text_.size() && text_[pos_] >= '0' && text_[pos_] <= '9') ++pos_;
        if (!parse_i64(text_.substr(start, pos_ - start), v.integer)) fail("bad integer " + quote(text_.substr(start, pos_ - start)));
        if (pos_ < text_.size() && (text_[pos_] == 'L' || text_[pos_] == 'l')) ++pos_;  // Python 2 long
        v.kind = PyValue::Kind::integer;
        return v;
    }
};

}  // namespace

PyValue parse_python_literal(const Cursor& c, std::string_view text, std::size_t base, const std::string& context) {
    return PyLiteralParser(c, text, base, context).parse();
}

}  // namespace io_detail
}  // namespace meniscus
