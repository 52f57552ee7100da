#include "config/stage_sections.hpp"

#include <string>

#include "epipole/core/yaml_fields.hpp"

namespace epipole::firmware::stages {

void read_stage_sections(std::span<const StageRow> rows, const YAML::Node& root,
                         const yaml::Fields& fields, StageSections& out) {
  for (const StageRow& row : rows) {
    if (row.definition->read_settings == nullptr) continue;
    const std::string name(protocol::stage_info(row.id).name);
    out.set(name,
            row.definition->read_settings(fields.optional_child(root, "", name.c_str()), fields));
  }
}

}  // namespace epipole::firmware::stages
