#pragma once
// Escaping text for XML and HTML (the viewer page's title, VTU attribute values).

#include <string>

namespace lambert {

/// `text` with & < > " replaced by their entities: safe in element text and in a
/// double-quoted attribute value of XML or HTML.
std::string xml_escape(const std::string& text);

}  // namespace lambert
