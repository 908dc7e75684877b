// A small XML scanner for the VTK XML formats: it walks the markup of a file in memory and reports start tags,
// end tags and character data to a visitor, without building a tree. Comments, <?...?> and <!...> declarations are
// skipped, CDATA sections are reported as character data, and nesting is checked (mismatched or unclosed elements
// are FormatErrors). The visitor can stop the scan at a start tag, for formats whose rest is not markup (VTK's
// <AppendedData>). Not a validating parser: DTDs, namespaces and entity definitions are ignored.
#pragma once
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "io/io_util.h"

namespace meniscus {
namespace io_detail {

struct XmlTag {
    std::string_view name;
    std::vector<std::pair<std::string_view, std::string_view>> attributes;  // values as written (entities not decoded)
    bool closing = false;       // </name>
    bool self_closing = false;  // <name ... />
    std::size_t pos = 0;        // of the '<'

    // The value of attribute `key`, or nullptr.
    const std::string_view* find(std::string_view key) const;
};

class XmlVisitor {
public:
    virtual ~XmlVisitor() = default;
    // A start tag (or an empty-element tag) whose enclosing elements are `open` (outermost first); `after` is the
    // position just past its '>'. Returning false ends the scan there, before the element is entered.
    virtual bool start_element(const XmlTag& tag, const std::vector<std::string_view>& open, std::size_t after) = 0;
    // An end tag; `depth` is the number of elements still open after it.
    virtual void end_element(std::string_view name, std::size_t depth) = 0;
    // Character data (or a CDATA section's content) inside `depth` open elements.
    virtual void text(TextRange range, std::size_t depth) = 0;
};

// Scans the whole source (after an optional UTF-8 byte order mark). Elements nested deeper than max_depth are
// refused, so that a hostile file cannot grow the element stack without bound.
void scan_xml(const Cursor& c, XmlVisitor& visitor, std::size_t max_depth);

// Replaces the five predefined XML entities and numeric character references below 128 (attribute values such as
// names rarely need more); anything else is kept as written.
std::string decode_xml_entities(std::string_view raw);

}  // namespace io_detail
}  // namespace meniscus
