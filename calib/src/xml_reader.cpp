#include "xml_reader.hpp"

#include <cstdint>

#include "epipole/core/error.hpp"

namespace epipole::calib::detail {

namespace {

constexpr int kMaxDepth = 64;  // FileStorage nests a few levels; deeper input is rejected

bool is_space(char c) {
  return c == ' ' || c == '\t' || c == '\n' || c == '\r';
}

bool is_name_char(char c) {
  const auto u = static_cast<unsigned char>(c);
  return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '_' ||
         c == '-' || c == '.' || c == ':' || u >= 0x80;
}

void append_utf8(std::string& out, std::uint32_t cp) {
  if (cp < 0x80) {
    out += static_cast<char>(cp);
  } else if (cp < 0x800) {
    out += static_cast<char>(0xC0 | (cp >> 6));
    out += static_cast<char>(0x80 | (cp & 0x3F));
  } else if (cp < 0x10000) {
    out += static_cast<char>(0xE0 | (cp >> 12));
    out += static_cast<char>(0x80 | ((cp >> 6) & 0x3F));
    out += static_cast<char>(0x80 | (cp & 0x3F));
  } else {
    out += static_cast<char>(0xF0 | (cp >> 18));
    out += static_cast<char>(0x80 | ((cp >> 12) & 0x3F));
    out += static_cast<char>(0x80 | ((cp >> 6) & 0x3F));
    out += static_cast<char>(0x80 | (cp & 0x3F));
  }
}

class Parser {
 public:
  Parser(std::string_view text, const std::string& file) : text_(text), file_(file) {}

  XmlElement document() {
    skip_misc();
    if (at_end() || peek() != '<') fail("no root element");
    XmlElement root = element(0);
    skip_misc();
    if (!at_end()) fail("content after the root element");
    return root;
  }

 private:
  [[noreturn]] void fail(const std::string& message) const {
    throw Error(cat(file_, ": line ", line_, ": malformed XML (", message, ")"));
  }

  bool at_end() const { return pos_ >= text_.size(); }
  char peek() const { return text_[pos_]; }
  bool starts_with(std::string_view s) const { return text_.substr(pos_).starts_with(s); }
  void advance(std::size_t n = 1) {
    for (std::size_t i = 0; i < n && pos_ < text_.size(); ++i) {
      if (text_[pos_] == '\n') ++line_;
      ++pos_;
    }
  }
  void skip_spaces() {
    while (!at_end() && is_space(peek())) advance();
  }
  // Advances past `end`, or fails.
  void skip_past(std::string_view end, const char* what) {
    const std::size_t found = text_.find(end, pos_);
    if (found == std::string_view::npos) fail(cat("unterminated ", what));
    advance(found + end.size() - pos_);
  }

  // Whitespace, comments, processing instructions and <!DOCTYPE ...> between elements.
  void skip_misc() {
    for (;;) {
      skip_spaces();
      if (starts_with("<?")) {
        skip_past("?>", "processing instruction");
      } else if (starts_with("<!--")) {
        skip_past("-->", "comment");
      } else if (starts_with("<!")) {
        skip_past(">", "declaration");
      } else {
        return;
      }
    }
  }

  std::string name() {
    const std::size_t start = pos_;
    while (!at_end() && is_name_char(peek())) advance();
    if (pos_ == start) fail("expected a name");
    return std::string(text_.substr(start, pos_ - start));
  }

  // Decodes an entity at pos_ ('&' ... ';').
  void entity(std::string& out) {
    const std::size_t end = text_.find(';', pos_);
    if (end == std::string_view::npos || end - pos_ > 12) fail("bad entity");
    const std::string_view e = text_.substr(pos_ + 1, end - pos_ - 1);
    if (e == "lt") {
      out += '<';
    } else if (e == "gt") {
      out += '>';
    } else if (e == "amp") {
      out += '&';
    } else if (e == "quot") {
      out += '"';
    } else if (e == "apos") {
      out += '\'';
    } else if (e.size() > 1 && e[0] == '#') {
      std::uint32_t cp = 0;
      const bool hex = e[1] == 'x' || e[1] == 'X';
      const std::string_view digits = e.substr(hex ? 2 : 1);
      if (digits.empty()) fail("bad character reference");
      for (char c : digits) {
        int v = -1;
        if (c >= '0' && c <= '9') v = c - '0';
        if (hex && c >= 'a' && c <= 'f') v = c - 'a' + 10;
        if (hex && c >= 'A' && c <= 'F') v = c - 'A' + 10;
        if (v < 0 || cp > 0x10FFFF) fail("bad character reference");
        cp = cp * (hex ? 16u : 10u) + static_cast<std::uint32_t>(v);
      }
      if (cp == 0 || cp > 0x10FFFF) fail("bad character reference");
      append_utf8(out, cp);
    } else {
      fail(cat("unknown entity &", std::string(e), ";"));
    }
    advance(end + 1 - pos_);
  }

  XmlElement element(int depth) {
    if (depth > kMaxDepth) fail("elements nested too deeply");
    XmlElement e;
    e.line = line_;
    advance();  // '<'
    e.name = name();
    for (;;) {
      skip_spaces();
      if (at_end()) fail(cat("unterminated start tag <", e.name, ">"));
      if (starts_with("/>")) {
        advance(2);
        return e;
      }
      if (peek() == '>') {
        advance();
        break;
      }
      std::string attribute = name();
      skip_spaces();
      if (at_end() || peek() != '=') fail(cat("attribute ", attribute, " has no value"));
      advance();
      skip_spaces();
      if (at_end() || (peek() != '"' && peek() != '\'')) fail("attribute value not quoted");
      const char quote = peek();
      advance();
      std::string value;
      while (!at_end() && peek() != quote) {
        if (peek() == '&') {
          entity(value);
        } else if (peek() == '<') {
          fail("'<' in an attribute value");
        } else {
          value += peek();
          advance();
        }
      }
      if (at_end()) fail("unterminated attribute value");
      advance();
      e.attributes.emplace_back(std::move(attribute), std::move(value));
    }
    // Content up to the matching end tag.
    for (;;) {
      if (at_end()) fail(cat("element <", e.name, "> is not closed"));
      if (starts_with("</")) {
        advance(2);
        const std::string end_name = name();
        skip_spaces();
        if (at_end() || peek() != '>') fail("bad end tag");
        advance();
        if (end_name != e.name) fail(cat("</", end_name, "> closes <", e.name, ">"));
        return e;
      }
      if (starts_with("<!--")) {
        skip_past("-->", "comment");
      } else if (starts_with("<![CDATA[")) {
        advance(9);
        const std::size_t end = text_.find("]]>", pos_);
        if (end == std::string_view::npos) fail("unterminated CDATA");
        e.text += text_.substr(pos_, end - pos_);
        advance(end + 3 - pos_);
      } else if (starts_with("<?")) {
        skip_past("?>", "processing instruction");
      } else if (peek() == '<') {
        e.children.push_back(element(depth + 1));
      } else if (peek() == '&') {
        entity(e.text);
      } else {
        e.text += peek();
        advance();
      }
    }
  }

  std::string_view text_;
  const std::string& file_;
  std::size_t pos_ = 0;
  int line_ = 1;
};

}  // namespace

const XmlElement* XmlElement::child(std::string_view child_name) const {
  for (const XmlElement& c : children) {
    if (c.name == child_name) return &c;
  }
  return nullptr;
}

std::string XmlElement::attribute(std::string_view attribute_name) const {
  for (const auto& [key, value] : attributes) {
    if (key == attribute_name) return value;
  }
  return {};
}

XmlElement parse_xml(std::string_view text, const std::string& file) {
  return Parser(text, file).document();
}

}  // namespace epipole::calib::detail
