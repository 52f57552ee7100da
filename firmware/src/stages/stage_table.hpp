#pragma once

// The pipeline's stages in the order they run, one row per switchable stage of the protocol's
// table (protocol/stages.hpp), each made by its file in this folder. Adding a stage: its row in
// protocol::kStages, its file here and its row below.

#include <array>
#include <memory>

#include "epipole/firmware/protocol/stages.hpp"
#include "stages/stage.hpp"

namespace epipole::firmware::stages {

using StageFactory = std::unique_ptr<PipelineStage> (*)(const StageContext& context);

std::unique_ptr<PipelineStage> make_rectify(const StageContext& context);    // rectify.cpp
std::unique_ptr<PipelineStage> make_corners(const StageContext& context);    // corners.cpp
std::unique_ptr<PipelineStage> make_disparity(const StageContext& context);  // disparity.cpp
std::unique_ptr<PipelineStage> make_sparse(const StageContext& context);     // sparse.cpp
std::unique_ptr<PipelineStage> make_detect(const StageContext& context);     // detect.cpp

struct StageRow {
  protocol::Stage id;
  StageFactory make;
};

inline constexpr std::array<StageRow, 5> kPipelineStages{{
    {protocol::Stage::rectify, make_rectify},
    {protocol::Stage::corners, make_corners},
    {protocol::Stage::disparity, make_disparity},
    {protocol::Stage::sparse, make_sparse},
    {protocol::Stage::detect, make_detect},
}};

// Every switchable stage of the protocol's table has its row, in the same order.
constexpr bool rows_follow_the_protocols_table() {
  std::size_t row = 0;
  for (const protocol::StageInfo& s : protocol::kStages) {
    if (s.kind != protocol::StageKind::switchable) continue;
    if (row == kPipelineStages.size() || kPipelineStages[row].id != s.id) return false;
    ++row;
  }
  return row == kPipelineStages.size();
}
static_assert(rows_follow_the_protocols_table(),
              "one row per switchable stage of protocol::kStages, in its order");

}  // namespace epipole::firmware::stages
