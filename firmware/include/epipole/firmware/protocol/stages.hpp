#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <string_view>

namespace epipole::protocol {

// The frame loop's stages, written once. A stage's id is its bit in a stage mask (the board
// file's `stages`, the set_stages command, a frame's stages that ran) and its slot in health's
// stage_us; kStages lists them in the order they run. Everything else is derived from this table:
// the board file's keys, the masks set_stages accepts, health's field names, the pipeline's
// order. Adding a stage: a row here (health grows: a new protocol version) and its file
// firmware/src/stages/<name>.cpp (docs/architecture.md).
enum class Stage : std::uint8_t {
  capture = 0,
  rectify = 1,
  corners = 2,
  disparity = 3,
  sparse = 4,
  detect = 5,
  ground = 6,
  odometry = 7,
  publish = 8,
  total = 9,
};

using StageMask = std::uint16_t;
constexpr StageMask stage_bit(Stage s) {
  return static_cast<StageMask>(1u << static_cast<unsigned>(s));
}
constexpr bool has_stage(StageMask mask, Stage s) {
  return (mask & stage_bit(s)) != 0;
}

enum class StageKind : std::uint8_t {
  always,      // runs on every pair (capture, publish)
  switchable,  // the board file and set_stages turn it on and off
  sum,         // not a stage: a time slot of health (total: capture to publish)
};

struct StageInfo {
  Stage id;
  std::string_view name;   // the board file's key under `stages`
  const char* time_field;  // health's field: the stage's mean time
  StageKind kind;
  StageMask needs;  // stages whose results it reads: it is skipped when they did not run
};

inline constexpr std::array<StageInfo, 10> kStages{{
    {Stage::capture, "capture", "capture_us", StageKind::always, 0},
    {Stage::rectify, "rectify", "rectify_us", StageKind::switchable, 0},
    {Stage::corners, "corners", "corners_us", StageKind::switchable, 0},
    {Stage::disparity, "disparity", "disparity_us", StageKind::switchable, 0},
    {Stage::sparse, "sparse", "sparse_us", StageKind::switchable, stage_bit(Stage::corners)},
    {Stage::detect, "detect", "detect_us", StageKind::switchable, 0},
    {Stage::ground, "ground", "ground_us", StageKind::switchable, stage_bit(Stage::disparity)},
    {Stage::odometry, "odometry", "odometry_us", StageKind::switchable, stage_bit(Stage::sparse)},
    {Stage::publish, "publish", "publish_us", StageKind::always, 0},
    {Stage::total, "total", "total_us", StageKind::sum, 0},
}};
inline constexpr int kStageCount = static_cast<int>(kStages.size());

constexpr bool stage_ids_are_their_rows() {
  for (std::size_t i = 0; i < kStages.size(); ++i) {
    if (static_cast<std::size_t>(kStages[i].id) != i) return false;
  }
  return true;
}
static_assert(stage_ids_are_their_rows(), "a stage's id is its row: its bit and its stage_us slot");

constexpr StageMask stages_of_kind(StageKind kind) {
  StageMask m = 0;
  for (const StageInfo& s : kStages) {
    if (s.kind == kind) m |= stage_bit(s.id);
  }
  return m;
}
// The stages that run on every pair, and every bit a stage mask may hold.
inline constexpr StageMask kAlwaysOnStages = stages_of_kind(StageKind::always);
inline constexpr StageMask kSwitchableStages = stages_of_kind(StageKind::switchable);
inline constexpr StageMask kAllStages = kAlwaysOnStages | kSwitchableStages;

constexpr const StageInfo& stage_info(Stage s) {
  return kStages[static_cast<std::size_t>(s)];
}

}  // namespace epipole::protocol
