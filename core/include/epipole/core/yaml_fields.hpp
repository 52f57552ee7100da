#pragma once

// Reading typed values out of a yaml-cpp tree with errors that name the file and the key: the
// configuration and calibration files share it (the epipole_yaml library).

#include <yaml-cpp/yaml.h>

#include <filesystem>
#include <initializer_list>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "epipole/core/data_directory.hpp"
#include "epipole/core/error.hpp"

namespace epipole::yaml {

class Fields {
 public:
  explicit Fields(std::string file) : file_(std::move(file)) {}

  const std::string& file() const { return file_; }

  // Throws Error("FILE: KEY: message").
  [[noreturn]] void fail(const std::string& key, const std::string& message) const;

  // Parses a whole document; malformed YAML is an Error naming the file, line and column.
  YAML::Node parse(const std::string& text) const;

  // `key` of the map at `path` ("" for the top level); missing or null is an Error.
  YAML::Node child(const YAML::Node& map, const std::string& path, const char* key) const;
  // The same, but absent (or null) gives an undefined node.
  YAML::Node optional_child(const YAML::Node& map, const std::string& path, const char* key) const;
  // Error for the first key of the map that is not in `known`.
  void only_keys(const YAML::Node& map, const std::string& path,
                 std::initializer_list<const char*> known) const;
  void only_keys(const YAML::Node& map, const std::string& path,
                 std::span<const std::string_view> known) const;
  void require_map(const YAML::Node& node, const std::string& path) const;

  double number(const YAML::Node& node, const std::string& key) const;  // finite
  int integer(const YAML::Node& node, const std::string& key) const;
  // The same within lo..hi, else Error("V is outside lo..hi").
  double number_in(const YAML::Node& node, const std::string& key, double lo, double hi) const;
  int integer_in(const YAML::Node& node, const std::string& key, int lo, int hi) const;
  std::string text(const YAML::Node& node, const std::string& key) const;
  // A flat sequence of finite numbers.
  std::vector<double> numbers(const YAML::Node& node, const std::string& key) const;
  // A sequence of `rows` sequences of `cols` finite numbers, row by row.
  std::vector<double> matrix(const YAML::Node& node, const std::string& key, int rows,
                             int cols) const;
  bool boolean(const YAML::Node& node, const std::string& key) const;
  // A path: ${NAME} is the environment variable NAME (${EPIPOLE_DATA_DIR} defaults to
  // default_data_directory()), a relative path starts in the file's folder; empty is an Error.
  std::filesystem::path path(const YAML::Node& node, const std::string& key) const;
  // A file name, a glob pattern (matched in name order) or a sequence of them; a pattern that
  // matches nothing is an Error.
  std::vector<std::filesystem::path> files(const YAML::Node& node, const std::string& key) const;

  // Calls read(value, "path.key") when the map at `path` has `key` (not null).
  template <typename Read>
  void if_present(const YAML::Node& map, const std::string& path, const char* key,
                  Read read) const {
    if (const YAML::Node n = optional_child(map, path, key); n.IsDefined()) {
      read(n, join(path, key));
    }
  }

  static std::string join(const std::string& path, const std::string& key) {
    return path.empty() ? key : path + "." + key;
  }

 private:
  std::string expand(const std::string& value, const std::string& key) const;
  std::string file_;
};

// The scalar as a finite double, or Error naming the key (`what` says what it is).
double finite_number(const std::string& scalar, const std::string& key, const std::string& file);

}  // namespace epipole::yaml
