#pragma once

// A small XML reader, enough for OpenCV's FileStorage XML files (no DTDs, no namespaces):
// elements, attributes, text with the five predefined entities and numeric character
// references, comments, processing instructions and CDATA. Internal to calib.

#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace epipole::calib::detail {

struct XmlElement {
  std::string name;
  std::vector<std::pair<std::string, std::string>> attributes;
  std::string text;  // the element's own character data, concatenated
  std::vector<XmlElement> children;
  int line = 0;  // where the start tag is, from 1

  // The first child called `child_name`, or nullptr.
  const XmlElement* child(std::string_view child_name) const;
  // The attribute's value, or "" when absent.
  std::string attribute(std::string_view attribute_name) const;
};

// The root element of a document. Malformed XML throws Error("FILE: line N: ...").
XmlElement parse_xml(std::string_view text, const std::string& file);

}  // namespace epipole::calib::detail
