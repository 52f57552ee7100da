#pragma once

// A stage of the pipeline: firmware/src/stages/<name>.cpp, named after its row of the protocol's
// table (protocol/stages.hpp), defines `extern constinit const StageDefinition <name>_stage`
// (declared by the generated stage_files.hpp, which it includes): how to make it
// from the board configuration with all its memory and, when it has settings of its own, how to
// read its section of the board file. Made, it adds its tasks to each pair's batch and writes
// its part of the results, its message among them. stage_table.hpp lists the stages in the
// order they run.

#include <array>
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <optional>
#include <span>
#include <string_view>

#include "epipole/calib/calibration.hpp"
#include "epipole/calib/triangulation.hpp"
#include "epipole/core/error.hpp"
#include "epipole/core/simd.hpp"
#include "epipole/core/task_batch.hpp"
#include "epipole/core/thread_pool.hpp"
#include "epipole/firmware/board_config.hpp"
#include "epipole/firmware/depth_grid.hpp"
#include "epipole/firmware/obstacles.hpp"
#include "epipole/firmware/pipeline.hpp"
#include "epipole/vision/cascade_model.hpp"

namespace YAML {
class Node;
}
namespace epipole::yaml {
class Fields;
}

namespace epipole::firmware {
class RigCorrection;  // epipole/firmware/rig_correction.hpp
}  // namespace epipole::firmware

namespace epipole::firmware::stages {

// What the stages of one pipeline share, made before them.
struct StageContext {
  const BoardConfig& board;
  const std::optional<calib::StereoCalibration>& calibration;
  SimdPath path;
  const vision::CascadeModel* cascade;      // instead of the board's file (tests, the host tool)
  ThreadPool& pool;                         // every stage's tasks
  const calib::Triangulator* triangulator;  // null without a calibration
  ObstacleSectors* obstacles;               // the depth's outputs: null without a calibration,
  DepthGrid* depth_grid;                    // and the grid without the board's
  RigCorrection* correction;                // the rig corrected while running (null without
                                            // a calibration)
};

// The settings a stage read from its own section of the board file (StageDefinition::
// read_settings): its defaults when the configuration was not read from a file (tests).
template <class Settings>
Settings settings_of(const StageContext& context, protocol::Stage stage) {
  const StageSettings* read = context.board.stage_sections.find(protocol::stage_info(stage).name);
  if (read == nullptr) return Settings{};
  const auto* settings = dynamic_cast<const Settings*>(read);
  require(settings != nullptr, "stage ", protocol::stage_info(stage).name,
          ": its section was read as other settings than it asks for");
  return *settings;
}

// One pair as the stages work on it (Pipeline::process).
struct PairWork {
  FrameResult& result;
  StageMask run;   // the stages that run on this pair
  NextPair* next;  // where the pair after it is found; null: nowhere
  TaskBatch& batch;
  std::array<int, protocol::kStageCount> parts;  // each stage's part of the batch, or kNoPart
};

class PipelineStage {
 public:
  virtual ~PipelineStage() = default;

  // Whether it can run at all (rectification needs a calibration, detection a cascade).
  virtual bool available() const { return true; }
  // A file it needs that is not there yet (a compiled cascade to make), else empty.
  virtual std::filesystem::path missing_file() const { return {}; }
  virtual std::size_t working_set_bytes() const = 0;

  // Called in the table's order on a pair it runs on. Before the batch: what every later stage
  // reads (the rectified images) and what may refuse the pair (throws: an image of a wrong
  // size), before any task is queued.
  virtual void prepare(PairWork& /*work*/) {}
  // Called instead of prepare() on a pair it does not run on (before any stage can throw).
  virtual void skip(PairWork& /*work*/) {}
  // Its tasks, after those of the stages before it (work.parts names theirs); returns its part
  // (TaskBatch::kNoPart: none). The callables must outlive the batch: members of the stage.
  virtual int add_tasks(PairWork& /*work*/) { return TaskBatch::kNoPart; }
  // Tasks that only fill the workers' last gaps, after every stage's own (on every pair, whether
  // the stage runs on it or not).
  virtual void fill_gaps(PairWork& /*work*/) {}
  // After the batch, on every pair (work.run says whether it ran): the rest of its results; its
  // time is its part's span plus what it adds.
  virtual void finish(PairWork& /*work*/) {}

  // The next pair starts a new sequence (what filters over time forgets the pairs before).
  virtual void forget_history() {}
  // The pair taken ahead (NextPair) will not be processed.
  virtual void drop_pair_ahead() {}
  // Pairs rectified ahead, and how many of them were then used.
  struct AheadCounts {
    std::uint64_t done = 0, used = 0;
  };
  virtual AheadCounts ahead() const { return {}; }
};

// What a stage's file defines, as `extern constinit const StageDefinition <name>_stage`.
struct StageDefinition {
  std::unique_ptr<PipelineStage> (*make)(const StageContext& context);
  // Reads its own top-level section of the board file, the key of its name (an undefined node
  // when the file has none: its defaults), throwing Error through `fields` for a bad value; null
  // when the stage has no settings of its own.
  std::unique_ptr<StageSettings> (*read_settings)(const YAML::Node& section,
                                                  const yaml::Fields& fields) = nullptr;
};

template <class Stage>
std::unique_ptr<PipelineStage> make_stage(const StageContext& context) {
  return std::make_unique<Stage>(context);
}

// A file of firmware/src/stages/ and what it defines (the generated stage_files.hpp).
struct StageFile {
  std::string_view name;
  const StageDefinition* definition;
};

// A stage in the order they run (stage_table.hpp).
struct StageRow {
  protocol::Stage id;
  const StageDefinition* definition;
};

}  // namespace epipole::firmware::stages
