#include "config/output_sections.hpp"

#include <algorithm>
#include <string>
#include <string_view>
#include <vector>

#include "epipole/core/yaml_fields.hpp"

namespace epipole::firmware::outputs {

void read_output_sections(std::span<const OutputFile> files, const YAML::Node& root,
                          const yaml::Fields& fields, OutputSections& out) {
  const YAML::Node section = fields.optional_child(root, "", "outputs");
  if (!section.IsDefined()) return;
  fields.require_map(section, "outputs");
  std::vector<std::string_view> names;
  std::string list;
  for (const OutputFile& file : files) {
    names.push_back(file.name);
    list += cat(list.empty() ? "" : ", ", file.name);
  }
  for (const auto& entry : section) {
    const std::string name = entry.first.IsScalar() ? entry.first.Scalar() : std::string("?");
    if (std::find(names.begin(), names.end(), name) == names.end()) {
      fields.fail(yaml::Fields::join("outputs", name),
                  cat("no output of that name (the outputs: ", list, ")"));
    }
  }
  fields.only_keys(section, "outputs", names);  // and no name twice
  for (const OutputFile& file : files) {
    const std::string name(file.name);
    const YAML::Node sub = section[name];
    if (!sub.IsDefined()) continue;
    if (!sub.IsNull()) fields.require_map(sub, yaml::Fields::join("outputs", name));
    out.set(name, file.definition->read_settings(sub, fields));
  }
}

}  // namespace epipole::firmware::outputs
