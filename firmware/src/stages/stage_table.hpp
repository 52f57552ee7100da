#pragma once

// The pipeline's stages in the order they run: one row per switchable stage of the protocol's
// table (protocol/stages.hpp), each defined by its file in this folder (stage_files.hpp,
// generated from the folder's files). Adding a stage: its row in protocol::kStages and its file
// here; a stage without its file, or a file without its row, does not compile.

#include <array>
#include <cstddef>

#include "epipole/firmware/protocol/stages.hpp"
#include "stage_files.hpp"
#include "stages/stage.hpp"

namespace epipole::firmware::stages {

constexpr std::size_t switchable_stage_count() {
  std::size_t n = 0;
  for (const protocol::StageInfo& s : protocol::kStages) {
    n += s.kind == protocol::StageKind::switchable ? 1 : 0;
  }
  return n;
}

// Each switchable stage of the protocol's table with its file's definition.
constexpr std::array<StageRow, switchable_stage_count()> pipeline_stages() {
  std::array<StageRow, switchable_stage_count()> rows{};
  std::size_t row = 0;
  for (const protocol::StageInfo& s : protocol::kStages) {
    if (s.kind != protocol::StageKind::switchable) continue;
    rows[row] = {s.id, nullptr};
    for (const StageFile& file : kStageFiles) {
      if (file.name == s.name) rows[row].definition = file.definition;
    }
    ++row;
  }
  return rows;
}
inline constexpr std::array<StageRow, switchable_stage_count()> kPipelineStages = pipeline_stages();

// By name: comparing the definitions' addresses is no constant expression under the sanitizers.
constexpr bool every_stage_has_its_file() {
  std::size_t matched = 0;
  for (const protocol::StageInfo& s : protocol::kStages) {
    if (s.kind != protocol::StageKind::switchable) continue;
    bool found = false;
    for (const StageFile& file : kStageFiles) found = found || file.name == s.name;
    if (!found) return false;
    ++matched;
  }
  return matched == kStageFiles.size();
}
static_assert(every_stage_has_its_file(),
              "each switchable stage of protocol::kStages has its file firmware/src/stages/"
              "<name>.cpp, and each file there is the stage of a row");

}  // namespace epipole::firmware::stages
