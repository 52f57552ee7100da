#include "epipole/firmware/pipeline.hpp"

#include "epipole/firmware/thread_roles.hpp"
#include "stages/stage_table.hpp"

namespace epipole::firmware {

using protocol::Stage;

namespace {

// The depth's outputs share the disparity's cells: their size and the depths they keep.
template <typename Config>
void depth_cells(Config& c, const BoardConfig& board, double min_depth_m, double max_depth_m,
                 int min_confidence) {
  c.width = board.width();
  c.height = board.height();
  c.max_disparity = board.stereo.max_disparity;
  c.min_depth_m = min_depth_m;
  c.max_depth_m = max_depth_m;
  c.min_confidence = min_confidence;
}

}  // namespace

// The obstacle sectors and the depth grid: what the disparity's end measures with a calibration.
void Pipeline::make_depth_outputs(const BoardConfig& board,
                                  const calib::StereoCalibration& calibration) {
  const BoardConfig::Obstacles& sectors = board.obstacles;
  ObstacleConfig o;
  depth_cells(o, board, sectors.min_depth_m, sectors.max_depth_m, sectors.min_confidence);
  o.columns = sectors.sectors;
  o.band_top = sectors.band_top;
  o.band_bottom = sectors.band_bottom;
  const auto& P1 = calibration.left.projection;
  obstacles_ = std::make_unique<ObstacleSectors>(o, *triangulator_, P1(0, 0), P1(0, 2));
  const BoardConfig::DepthGrid& grid = board.depth_grid;
  if (grid.columns > 0) {
    DepthCellsConfig g;
    depth_cells(g, board, grid.min_depth_m, grid.max_depth_m, grid.min_confidence);
    g.columns = grid.columns;
    g.rows = grid.rows;
    depth_grid_ = std::make_unique<DepthGrid>(
        g, *triangulator_, RectifiedPinhole{P1(0, 0), P1(0, 2), P1(1, 1), P1(1, 2)});
  }
}

Pipeline::Pipeline(const BoardConfig& board,
                   const std::optional<calib::StereoCalibration>& calibration, SimdPath path,
                   const vision::CascadeModel* cascade)
    : pool_(std::make_unique<ThreadPool>(board.threads.count,
                                         [] { enter_thread_role_or_say(ThreadRole::compute); })) {
  if (calibration) {
    // Only point() and depth() are used: no point image is needed.
    triangulator_ = std::make_unique<calib::Triangulator>(calibration->Q, 1, 1);
    make_depth_outputs(board, *calibration);
    correction_ = std::make_unique<RigCorrection>(*calibration, board);
  }
  const stages::StageContext context{board,
                                     calibration,
                                     path,
                                     cascade,
                                     *pool_,
                                     triangulator_.get(),
                                     obstacles_.get(),
                                     depth_grid_.get(),
                                     correction_.get()};
  available_ = protocol::kAlwaysOnStages;
  for (const stages::StageRow& row : stages::kPipelineStages) {
    auto& stage = stages_[static_cast<std::size_t>(row.id)];
    stage = row.definition->make(context);
    if (stage->available()) available_ |= stage_bit(row.id);
  }
}

Pipeline::~Pipeline() = default;

void Pipeline::add_memory(MemoryReport& report) const {
  for (const stages::StageRow& row : stages::kPipelineStages) {
    const stages::PipelineStage& stage = *stages_[static_cast<std::size_t>(row.id)];
    if (stage.available()) {
      report.add(std::string(protocol::stage_info(row.id).name), stage.working_set_bytes());
    }
  }
}

void Pipeline::reset_history() {
  for (const auto& stage : stages_) {
    if (stage) stage->forget_history();
  }
}

void Pipeline::drop_pair_ahead() {
  for (const auto& stage : stages_) {
    if (stage) stage->drop_pair_ahead();
  }
}

std::filesystem::path Pipeline::missing_cascade() const {
  return stages_[static_cast<std::size_t>(Stage::detect)]->missing_file();
}

std::uint64_t Pipeline::pairs_rectified_ahead() const {
  std::uint64_t n = 0;
  for (const auto& stage : stages_) n += stage ? stage->ahead().done : 0;
  return n;
}

std::uint64_t Pipeline::pairs_used_ahead() const {
  std::uint64_t n = 0;
  for (const auto& stage : stages_) n += stage ? stage->ahead().used : 0;
  return n;
}

// The stages of a pair on the one pool, in the table's order: each prepares what the later ones
// read (the rectification of both images, in row bands, unless it was done ahead) or what may
// refuse the pair; then one batch of every stage's tasks in the order they should start (the
// corners of both images, the disparity's stripes, the sparse matching once the corners are
// there, the cascade's pyramid levels), and last what fills the workers' gaps (the next pair's
// rectification); then each stage's end (the detections and their depths).
const FrameResult& Pipeline::process(GrayView left, GrayView right, std::uint32_t frame,
                                     hal::Nanoseconds trigger_ns, StageMask enabled,
                                     NextPair* next) {
  FrameResult& r = result_;
  r = FrameResult{};
  r.frame = frame;
  r.trigger_ns = trigger_ns;
  r.left_raw = r.left = left;
  r.right_raw = r.right = right;
  // A stage runs when it is on, possible here, and what it reads runs.
  StageMask run = stage_bit(Stage::capture);
  for (const protocol::StageInfo& s : protocol::kStages) {
    const bool wanted = s.kind == protocol::StageKind::switchable &&
                        protocol::has_stage(enabled & available_, s.id);
    if (wanted && (run & s.needs) == s.needs) run |= stage_bit(s.id);
  }
  stages::PairWork work{r, run, next, batch_, {}};
  work.parts.fill(TaskBatch::kNoPart);
  batch_.clear();
  const auto runs = [&](const stages::StageRow& row) { return protocol::has_stage(run, row.id); };
  const auto stage = [&](const stages::StageRow& row) -> stages::PipelineStage& {
    return *stages_[static_cast<std::size_t>(row.id)];
  };
  for (const stages::StageRow& row : stages::kPipelineStages) {
    if (!runs(row)) stage(row).skip(work);
  }
  for (const stages::StageRow& row : stages::kPipelineStages) {
    if (runs(row)) stage(row).prepare(work);
  }
  for (const stages::StageRow& row : stages::kPipelineStages) {
    if (runs(row)) work.parts[static_cast<std::size_t>(row.id)] = stage(row).add_tasks(work);
  }
  for (const stages::StageRow& row : stages::kPipelineStages) stage(row).fill_gaps(work);
  batch_.run(*pool_);
  for (const stages::StageRow& row : stages::kPipelineStages) {
    const int part = work.parts[static_cast<std::size_t>(row.id)];
    r.times[static_cast<std::size_t>(row.id)] += batch_.span_ns(part, part);
    stage(row).finish(work);
  }
  r.stages = run;
  return r;
}

}  // namespace epipole::firmware
