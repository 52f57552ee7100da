#include "epipole/core/yaml_fields.hpp"

#include <glob.h>

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstdlib>
#include <limits>
#include <system_error>

namespace epipole::yaml {

namespace {

bool non_finite_spelling(std::string s) {
  for (char& c : s) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  if (!s.empty() && (s[0] == '+' || s[0] == '-')) s.erase(0, 1);
  return s == ".nan" || s == ".inf" || s == "nan" || s == "inf" || s == "infinity";
}

std::string kind(const YAML::Node& node) {
  switch (node.Type()) {
    case YAML::NodeType::Sequence:
      return "a sequence";
    case YAML::NodeType::Map:
      return "a map";
    case YAML::NodeType::Scalar:
      return "'" + node.Scalar() + "'";
    default:
      return "nothing";
  }
}

}  // namespace

double finite_number(const std::string& scalar, const std::string& key, const std::string& file) {
  const std::string where = file + ": " + key + ": ";
  if (non_finite_spelling(scalar)) {
    throw Error(cat(where, "'", scalar, "' is not a finite number"));
  }
  // std::from_chars: locale-independent, the whole scalar must be the number. A leading '+'
  // is allowed as YAML allows it.
  const char* first = scalar.data();
  const char* last = scalar.data() + scalar.size();
  if (first != last && *first == '+') ++first;
  double value = 0;
  const auto [end, error] = std::from_chars(first, last, value);
  if (error == std::errc::result_out_of_range) {
    throw Error(cat(where, "'", scalar, "' is out of the range of a double"));
  }
  if (error != std::errc() || end != last || first == last) {
    throw Error(cat(where, "'", scalar, "' is not a number"));
  }
  if (!std::isfinite(value)) throw Error(cat(where, "'", scalar, "' is not a finite number"));
  return value;
}

void Fields::fail(const std::string& key, const std::string& message) const {
  throw Error(cat(file_, ": ", key, ": ", message));
}

YAML::Node Fields::parse(const std::string& text) const {
  try {
    return YAML::Load(text);
  } catch (const YAML::Exception& e) {
    throw Error(cat(file_, ": line ", e.mark.line + 1, ", column ", e.mark.column + 1,
                    ": malformed YAML (", e.msg, ")"));
  }
}

void Fields::require_map(const YAML::Node& node, const std::string& path) const {
  if (!node.IsMap()) {
    if (path.empty()) throw Error(cat(file_, ": expected a YAML map of keys, found ", kind(node)));
    fail(path, "expected a map of keys, found " + kind(node));
  }
}

YAML::Node Fields::optional_child(const YAML::Node& map, const std::string& path,
                                  const char* key) const {
  require_map(map, path);
  const YAML::Node node = map[key];
  if (!node.IsDefined() || node.IsNull()) return YAML::Node(YAML::NodeType::Undefined);
  return node;
}

YAML::Node Fields::child(const YAML::Node& map, const std::string& path, const char* key) const {
  require_map(map, path);
  const YAML::Node node = map[key];
  if (!node.IsDefined()) throw Error(cat(file_, ": missing key '", join(path, key), "'"));
  if (node.IsNull()) fail(join(path, key), "has no value");
  return node;
}

void Fields::only_keys(const YAML::Node& map, const std::string& path,
                       std::initializer_list<const char*> known) const {
  std::vector<std::string_view> names(known.begin(), known.end());
  only_keys(map, path, names);
}

void Fields::only_keys(const YAML::Node& map, const std::string& path,
                       std::span<const std::string_view> known) const {
  require_map(map, path);
  std::vector<std::string> seen;
  for (const auto& entry : map) {
    const std::string name = entry.first.IsScalar() ? entry.first.Scalar() : std::string("?");
    if (std::find(known.begin(), known.end(), name) == known.end()) {
      throw Error(cat(file_, ": unknown key '", join(path, name), "'"));
    }
    // YAML readers keep one of a repeated key's values, silently: a second `stereo:` block
    // added at the end of a board file would be ignored.
    if (std::find(seen.begin(), seen.end(), name) != seen.end()) {
      throw Error(cat(file_, ": line ", entry.first.Mark().line + 1, ": key '", join(path, name),
                      "' appears twice"));
    }
    seen.push_back(name);
  }
}

double Fields::number(const YAML::Node& node, const std::string& key) const {
  if (!node.IsScalar()) fail(key, "expected a number, found " + kind(node));
  return finite_number(node.Scalar(), key, file_);
}

int Fields::integer(const YAML::Node& node, const std::string& key) const {
  if (!node.IsScalar()) fail(key, "expected an integer, found " + kind(node));
  const std::string& s = node.Scalar();
  long long value = 0;
  const auto [end, error] = std::from_chars(s.data(), s.data() + s.size(), value);
  if (error != std::errc() || end != s.data() + s.size() || s.empty()) {
    fail(key, "'" + s + "' is not an integer");
  }
  if (value < std::numeric_limits<int>::min() || value > std::numeric_limits<int>::max()) {
    fail(key, "'" + s + "' is out of range");
  }
  return static_cast<int>(value);
}

double Fields::number_in(const YAML::Node& node, const std::string& key, double lo,
                         double hi) const {
  const double v = number(node, key);
  if (v < lo || v > hi) fail(key, cat(v, " is outside ", lo, "..", hi));
  return v;
}

int Fields::integer_in(const YAML::Node& node, const std::string& key, int lo, int hi) const {
  const int v = integer(node, key);
  if (v < lo || v > hi) fail(key, cat(v, " is outside ", lo, "..", hi));
  return v;
}

std::string Fields::text(const YAML::Node& node, const std::string& key) const {
  if (!node.IsScalar()) fail(key, "expected a string, found " + kind(node));
  return node.Scalar();
}

std::vector<double> Fields::numbers(const YAML::Node& node, const std::string& key) const {
  if (!node.IsSequence()) fail(key, "expected a sequence of numbers, found " + kind(node));
  std::vector<double> values;
  values.reserve(node.size());
  for (std::size_t i = 0; i < node.size(); ++i) {
    values.push_back(number(node[i], cat(key, "[", i, "]")));
  }
  return values;
}

std::vector<double> Fields::matrix(const YAML::Node& node, const std::string& key, int rows,
                                   int cols) const {
  const std::string shape = cat(rows, "x", cols, " matrix (", rows, " rows of ", cols, " numbers)");
  if (!node.IsSequence()) fail(key, "expected a " + shape + ", found " + kind(node));
  if (node.size() != static_cast<std::size_t>(rows)) {
    fail(key, cat("expected a ", shape, ", found ", node.size(), " rows"));
  }
  std::vector<double> m(static_cast<std::size_t>(rows) * static_cast<std::size_t>(cols));
  for (int r = 0; r < rows; ++r) {
    const YAML::Node row = node[static_cast<std::size_t>(r)];
    if (!row.IsSequence() || row.size() != static_cast<std::size_t>(cols)) {
      fail(key, cat("expected a ", shape, ", row ", r + 1, " is ",
                    row.IsSequence() ? cat(row.size(), " numbers") : kind(row)));
    }
    for (int c = 0; c < cols; ++c) {
      m[static_cast<std::size_t>(r * cols + c)] =
          number(row[static_cast<std::size_t>(c)], cat(key, "[", r, "][", c, "]"));
    }
  }
  return m;
}

bool Fields::boolean(const YAML::Node& node, const std::string& key) const {
  if (node.IsScalar()) {
    const std::string& s = node.Scalar();
    if (s == "true" || s == "yes" || s == "on") return true;
    if (s == "false" || s == "no" || s == "off") return false;
  }
  fail(key, "expected true or false, found " + kind(node));
}

std::string Fields::expand(const std::string& value, const std::string& key) const {
  std::string out;
  for (std::size_t i = 0; i < value.size(); ++i) {
    if (value.compare(i, 2, "${") != 0) {
      out += value[i];
      continue;
    }
    const std::size_t end = value.find('}', i);
    if (end == std::string::npos) fail(key, cat("'", value, "': unterminated ${"));
    const std::string name = value.substr(i + 2, end - i - 2);
    if (name == "EPIPOLE_DATA_DIR") {
      out += default_data_directory().string();
    } else if (const char* v = std::getenv(name.c_str()); v != nullptr) {
      out += v;
    } else {
      fail(key, cat("'", value, "': environment variable ", name, " is not set"));
    }
    i = end;
  }
  return out;
}

std::filesystem::path Fields::path(const YAML::Node& node, const std::string& key) const {
  const std::string value = text(node, key);
  if (value.empty()) fail(key, "is an empty path");
  std::filesystem::path p = expand(value, key);
  return p.is_absolute() ? p : std::filesystem::path(file_).parent_path() / p;
}

std::vector<std::filesystem::path> Fields::files(const YAML::Node& node,
                                                 const std::string& key) const {
  std::vector<std::filesystem::path> out;
  const auto add = [&](const YAML::Node& item, const std::string& k) {
    const std::filesystem::path p = path(item, k);
    if (p.string().find_first_of("*?[") == std::string::npos) {
      out.push_back(p);
      return;
    }
    glob_t g{};
    const int rc = ::glob(p.c_str(), 0, nullptr, &g);
    for (std::size_t i = 0; rc == 0 && i < g.gl_pathc; ++i) out.emplace_back(g.gl_pathv[i]);
    globfree(&g);
    if (rc != 0) fail(k, cat("no file matches '", p.string(), "'"));
  };
  if (node.IsSequence()) {
    for (std::size_t i = 0; i < node.size(); ++i) add(node[i], cat(key, "[", i, "]"));
  } else {
    add(node, key);
  }
  return out;
}

}  // namespace epipole::yaml
