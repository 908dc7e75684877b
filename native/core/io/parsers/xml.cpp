#include "io/parsers/xml.h"

#include <algorithm>

namespace meniscus {
namespace io_detail {

const std::string_view* XmlTag::find(std::string_view key) const {
    for (const auto& a : attributes)
        if (a.first == key) return &a.second;
    return nullptr;
}

namespace {

// Element and attribute names: anything up to white space or markup.
bool is_name_char(unsigned char ch) {
    return !Cursor::is_space(ch) && ch != '>' && ch != '/' && ch != '=' && ch != '<' && ch != '"' && ch != '\'';
}

std::string short_name(std::string_view name) { return std::string(name.substr(0, 40)); }

class XmlScanner {
public:
    XmlScanner(const Cursor& c, XmlVisitor& visitor, std::size_t max_depth)
        : c_(c), d_(c.source().data), size_(c.size()), visitor_(visitor), max_depth_(max_depth) {}

    void run() {
        std::size_t i = size_ >= 3 && std::memcmp(d_, "\xef\xbb\xbf", 3) == 0 ? 3 : 0;
        while (i < size_) {
            if (d_[i] != '<')
                i = character_data(i);
            else if (starts_with(i, "<!--"))
                i = skip_past(i, 4, "-->", "XML comment");
            else if (starts_with(i, "<![CDATA["))
                i = cdata(i);
            else if (i + 1 < size_ && (d_[i + 1] == '?' || d_[i + 1] == '!'))  // <?xml ...?>, <!DOCTYPE ...>
                i = skip_past(i, 0, ">", "XML declaration");
            else if (!tag(i, i))
                return;
        }
        if (!open_.empty())
            c_.fail("truncated at " + c_.where(size_) + ": the XML element <" + short_name(open_.back()) + "> is not closed");
    }

private:
    const Cursor& c_;
    const unsigned char* d_;
    std::size_t size_;
    XmlVisitor& visitor_;
    std::size_t max_depth_;
    std::vector<std::string_view> open_;  // names of the open elements, outermost first

    [[noreturn]] void fail_at(std::size_t pos, const std::string& what) const { c_.fail(what + " at " + c_.where(pos)); }

    bool starts_with(std::size_t i, std::string_view prefix) const { return c_.view(i, std::min(size_, i + prefix.size())) == prefix; }

    std::size_t find(std::string_view needle, std::size_t from) const {
        std::size_t at = c_.view(0, size_).find(needle, from);
        return at == std::string_view::npos ? size_ : at;
    }

    std::size_t character_data(std::size_t i) {
        std::size_t end = i;
        while (end < size_ && d_[end] != '<') ++end;
        visitor_.text({i, end}, open_.size());
        return end;
    }

    // Skips markup that starts at `i` (its opening is `skip` bytes long) and ends with `close`.
    std::size_t skip_past(std::size_t i, std::size_t skip, std::string_view close, const char* what) {
        std::size_t end = find(close, i + skip);
        if (end >= size_)
            c_.fail("truncated at " + c_.where(size_) + ": the " + what + " started at " + c_.where(i) + " is not closed");
        return end + close.size();
    }

    std::size_t cdata(std::size_t i) {
        std::size_t after = skip_past(i, 9, "]]>", "CDATA section");
        visitor_.text({i + 9, after - 3}, open_.size());
        return after;
    }

    // A start, end or empty-element tag at `pos`; false when the visitor ends the scan. `next` is set past the tag.
    bool tag(std::size_t pos, std::size_t& next) {
        XmlTag tag;
        next = parse_tag(pos, tag);
        if (tag.closing) {
            if (open_.empty() || open_.back() != tag.name)
                fail_at(pos, "closing tag </" + short_name(tag.name) + "> does not match " +
                                 (open_.empty() ? std::string("any open element") : "<" + short_name(open_.back()) + ">"));
            open_.pop_back();
            visitor_.end_element(tag.name, open_.size());
            return true;
        }
        if (!visitor_.start_element(tag, open_, next)) return false;
        if (!tag.self_closing) {
            if (open_.size() >= max_depth_) fail_at(pos, "XML nested more than " + std::to_string(max_depth_) + " levels deep");
            open_.push_back(tag.name);
        }
        return true;
    }

    // Parses the tag starting at '<' at `pos`; returns the position after '>'.
    std::size_t parse_tag(std::size_t pos, XmlTag& tag) const {
        tag.pos = pos;
        std::size_t i = pos + 1;
        if (i < size_ && d_[i] == '/') {
            tag.closing = true;
            ++i;
        }
        std::size_t start = i;
        while (i < size_ && is_name_char(d_[i])) ++i;
        if (i == start) fail_at(pos, "malformed XML tag");
        tag.name = c_.view(start, i);
        while (true) {
            while (i < size_ && Cursor::is_space(d_[i])) ++i;
            if (i >= size_)
                c_.fail("truncated at " + c_.where(size_) + ": the XML tag <" + short_name(tag.name) + "> started at " +
                        c_.where(pos) + " is not closed");
            if (d_[i] == '>') return i + 1;
            if (d_[i] == '/' && i + 1 < size_ && d_[i + 1] == '>' && !tag.closing) {
                tag.self_closing = true;
                return i + 2;
            }
            if (tag.closing) fail_at(i, "unexpected character in the closing tag </" + short_name(tag.name) + ">");
            i = parse_attribute(i, tag);
        }
    }

    // One key="value" (or key='value') pair at `i`; returns the position after it.
    std::size_t parse_attribute(std::size_t i, XmlTag& tag) const {
        std::size_t key_start = i;
        while (i < size_ && is_name_char(d_[i])) ++i;
        if (i == key_start) fail_at(i, "malformed attribute in the XML tag <" + short_name(tag.name) + ">");
        std::string_view key = c_.view(key_start, i);
        while (i < size_ && Cursor::is_space(d_[i])) ++i;
        if (i >= size_ || d_[i] != '=') fail_at(i, "attribute " + quote(key) + " without a value");
        ++i;
        while (i < size_ && Cursor::is_space(d_[i])) ++i;
        if (i >= size_ || (d_[i] != '"' && d_[i] != '\'')) fail_at(i, "attribute " + quote(key) + " without a quoted value");
        unsigned char q = d_[i++];
        std::size_t value_start = i;
        while (i < size_ && d_[i] != q) ++i;
        if (i >= size_) c_.fail("truncated at " + c_.where(size_) + ": the value of attribute " + quote(key) + " is not closed");
        tag.attributes.emplace_back(key, c_.view(value_start, i));
        return i + 1;
    }
};

// The character an entity name (between '&' and ';') stands for, or 0 when it is not one we decode.
char entity_char(std::string_view entity) {
    if (entity == "lt") return '<';
    if (entity == "gt") return '>';
    if (entity == "amp") return '&';
    if (entity == "quot") return '"';
    if (entity == "apos") return '\'';
    std::uint64_t code = 0;
    if (entity.size() >= 2 && entity[0] == '#' && entity[1] != 'x' && parse_u64(entity.substr(1), code) && code > 0 && code < 128)
        return static_cast<char>(code);
    return 0;
}

}  // namespace

void scan_xml(const Cursor& c, XmlVisitor& visitor, std::size_t max_depth) { XmlScanner(c, visitor, max_depth).run(); }

std::string decode_xml_entities(std::string_view raw) {
    std::string out;
    for (std::size_t i = 0; i < raw.size(); ++i) {
        std::size_t semi = raw[i] == '&' ? raw.find(';', i) : std::string_view::npos;
        char c = semi != std::string_view::npos && semi - i <= 8 ? entity_char(raw.substr(i + 1, semi - i - 1)) : 0;
        if (c) {
            out += c;
            i = semi;
        } else {
            out += raw[i];
        }
    }
    return out;
}

}  // namespace io_detail
}  // namespace meniscus
