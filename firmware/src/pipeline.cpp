#include "epipole/firmware/pipeline.hpp"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <variant>

#include "epipole/core/data_directory.hpp"
#include "epipole/core/error.hpp"
#include "epipole/firmware/cascade_file.hpp"
#include "epipole/firmware/stereo_rectification.hpp"
#include "epipole/firmware/thread_roles.hpp"
#include "epipole/vision/fast.hpp"
#include "epipole/vision/harris.hpp"
#include "epipole/vision/remap.hpp"
#include "steady_time.hpp"

namespace epipole::firmware {

using detail::steady_now;

using protocol::Stage;

namespace {

// One corner detector per image, FAST or Harris as the board says.
class CornerDetector {
 public:
  CornerDetector(const BoardConfig& board, SimdPath path) {
    if (board.corners.detector == BoardConfig::CornerDetector::fast) {
      vision::FastConfig c;
      c.width = board.width();
      c.height = board.height();
      c.threshold = board.corners.threshold;
      c.max_corners = board.corners.max_corners;
      c.grid_columns = c.grid_rows = board.corners.grid;
      detector_.emplace<vision::FastDetector>(c, path);
    } else {
      vision::HarrisConfig c;
      c.width = board.width();
      c.height = board.height();
      c.max_corners = board.corners.max_corners;
      detector_.emplace<vision::HarrisDetector>(c, path);
    }
  }
  std::span<const vision::Corner> detect(GrayView image) {
    return std::visit(
        [&](auto& d) -> std::span<const vision::Corner> {
          if constexpr (std::is_same_v<std::decay_t<decltype(d)>, std::monostate>) {
            return {};
          } else {
            return d.detect(image);
          }
        },
        detector_);
  }
  std::size_t working_set_bytes() const {
    return std::visit(
        [](const auto& d) -> std::size_t {
          if constexpr (std::is_same_v<std::decay_t<decltype(d)>, std::monostate>) {
            return 0;
          } else {
            return d.working_set_bytes();
          }
        },
        detector_);
  }

 private:
  std::variant<std::monostate, vision::FastDetector, vision::HarrisDetector> detector_;
};

}  // namespace

struct Pipeline::Stages {
  std::optional<StereoRectifiers> rectifiers;
  CornerDetector corners_left, corners_right;
  std::unique_ptr<vision::StereoMatcher> matcher;
  vision::SparseStereoMatcher sparse;
  Stages(const BoardConfig& board, SimdPath path)
      : corners_left(board, path), corners_right(board, path), sparse(sparse_config(board), path) {}
  static vision::SparseStereoConfig sparse_config(const BoardConfig& board) {
    vision::SparseStereoConfig c;
    c.width = board.width();
    c.height = board.height();
    c.max_disparity = board.stereo.max_disparity;
    c.row_tolerance = board.sparse.row_tolerance;
    c.ratio = board.sparse.ratio;
    c.max_distance = board.sparse.max_distance;
    c.max_corners = board.corners.max_corners;
    c.max_matches = board.sparse.max_matches;
    return c;
  }
};

std::filesystem::path opencv_cascade_xml(const std::filesystem::path& compiled) {
  for (const char* family : {"haarcascades", "lbpcascades"}) {
    std::filesystem::path candidate = default_data_directory() / "cascades" / family;
    candidate /= compiled.stem().string() + ".xml";
    std::error_code ec;
    if (std::filesystem::exists(candidate, ec)) return candidate;
  }
  return {};
}

std::string cascade_compile_command(const std::filesystem::path& compiled) {
  const std::filesystem::path xml = opencv_cascade_xml(compiled);
  return cat("epipole cascade-compile ", xml.empty() ? "CASCADE.xml" : xml.string(), " ",
             compiled.string());
}

namespace {

vision::CascadeModel board_cascade(const BoardConfig& board) {
  const std::filesystem::path& file = board.detector.cascade;
  if (file.extension() == ".xml") {
    throw Error(cat("detector.cascade: ", file.string(),
                    " is OpenCV's cascade XML; the firmware reads compiled cascades: run "
                    "`epipole cascade-compile ",
                    file.string(), " ",
                    std::filesystem::path(file).replace_extension(".bin").string(),
                    "` and name the .bin"));
  }
  return load_compiled_cascade(file);
}

vision::CascadeConfig cascade_config(const BoardConfig& board) {
  vision::CascadeConfig c;
  c.max_width = board.width();
  c.max_height = board.height();
  c.scale_factor = board.detector.scale_factor;
  c.min_neighbors = board.detector.min_neighbors;
  c.min_object_width = c.min_object_height = board.detector.min_size;
  c.max_object_width = c.max_object_height = board.detector.max_size;
  c.max_detections = protocol::kMaxDetections;
  c.workers = board.threads.count;
  return c;
}

}  // namespace

Pipeline::Pipeline(const BoardConfig& board,
                   const std::optional<calib::StereoCalibration>& calibration, SimdPath path,
                   const vision::CascadeModel* cascade)
    : stages_(std::make_unique<Stages>(board, path)),
      pool_(std::make_unique<ThreadPool>(board.threads.count,
                                         [] { enter_thread_role_or_say(ThreadRole::compute); })),
      calibration_health_(board.sparse.max_matches) {
  available_ = stage_bit(Stage::capture) | stage_bit(Stage::publish) | stage_bit(Stage::corners) |
               stage_bit(Stage::disparity) | stage_bit(Stage::sparse);
  points_.resize(static_cast<std::size_t>(board.sparse.max_matches));
  point_order_.resize(points_.size());
  rectified_matches_.resize(points_.size());
  max_points_ = board.sparse.max_points;
  if (calibration) {
    require(calibration->width == board.width() && calibration->height == board.height(),
            "calibration ", board.calibration.string(), " is for ", calibration->width, "x",
            calibration->height, " images but the cameras deliver ", board.width(), "x",
            board.height());
    stages_->rectifiers.emplace(
        make_stereo_rectifiers(*calibration, path, 0, /*own_output=*/false));
    for (std::size_t slot = 0; slot < 2; ++slot) {
      rectified_left_[slot] = GrayImage(board.width(), board.height());
      rectified_right_[slot] = GrayImage(board.width(), board.height());
    }
    available_ |= stage_bit(Stage::rectify);
    // Only point() and depth() are used: no point image is needed.
    triangulator_ = std::make_unique<calib::Triangulator>(calibration->Q, 1, 1);
  }
  vision::StereoConfig stereo = board.stereo;
  stereo.width = board.width();
  stereo.height = board.height();
  if (calibration) {
    const auto cells = [&](DepthCellsConfig& c, double min_depth_m, double max_depth_m,
                           int min_confidence) {
      c.width = board.width();
      c.height = board.height();
      c.max_disparity = stereo.max_disparity;
      c.min_depth_m = min_depth_m;
      c.max_depth_m = max_depth_m;
      c.min_confidence = min_confidence;
    };
    const BoardConfig::Obstacles& sectors = board.obstacles;
    ObstacleConfig o;
    cells(o, sectors.min_depth_m, sectors.max_depth_m, sectors.min_confidence);
    o.columns = sectors.sectors;
    o.band_top = sectors.band_top;
    o.band_bottom = sectors.band_bottom;
    const BoardConfig::DepthGrid& grid = board.depth_grid;
    stereo.confidence = sectors.min_confidence > 0 || (grid.columns > 0 && grid.min_confidence > 0);
    const auto& P1 = calibration->left.projection;
    obstacles_ = std::make_unique<ObstacleSectors>(o, *triangulator_, P1(0, 0), P1(0, 2));
    if (grid.columns > 0) {
      DepthCellsConfig g;
      cells(g, grid.min_depth_m, grid.max_depth_m, grid.min_confidence);
      g.columns = grid.columns;
      g.rows = grid.rows;
      depth_grid_ = std::make_unique<DepthGrid>(
          g, *triangulator_, RectifiedPinhole{P1(0, 0), P1(0, 2), P1(1, 1), P1(1, 2)});
    }
  }
  // The detector, when the board has a cascade (or one is given) and detection is on; a
  // compiled cascade that was not made yet leaves detection off until it is.
  const bool board_cascade_named =
      protocol::has_stage(board.stages, Stage::detect) && !board.detector.cascade.empty();
  std::error_code ec;
  if (cascade == nullptr && board_cascade_named && board.detector.cascade.extension() != ".xml" &&
      !std::filesystem::exists(board.detector.cascade, ec)) {
    missing_cascade_ = board.detector.cascade;
  } else if (cascade != nullptr || board_cascade_named) {
    const vision::CascadeModel model = cascade != nullptr ? *cascade : board_cascade(board);
    detector_ = std::make_unique<vision::CascadeDetector>(model, cascade_config(board), path);
    depths_.resize(static_cast<std::size_t>(protocol::kMaxDetections));
    if (triangulator_) {
      depth_estimator_ =
          std::make_unique<DetectionDepthEstimator>(*triangulator_, stereo.max_disparity);
    }
    available_ |= stage_bit(Stage::detect);
  }
  // One pool for every stage: threads.count workers, one per CPU, the disparity in as many
  // stripes.
  stereo.threads = board.threads.count;
  stages_->matcher = std::make_unique<vision::StereoMatcher>(stereo, path, pool_.get());
}

Pipeline::~Pipeline() = default;

void Pipeline::add_memory(MemoryReport& report) const {
  const auto name = [](Stage s) { return std::string(protocol::stage_info(s).name); };
  if (stages_->rectifiers) {
    std::size_t images = 0;
    for (std::size_t slot = 0; slot < 2; ++slot) {
      images += rectified_left_[slot].size_bytes() + rectified_right_[slot].size_bytes();
    }
    report.add(name(Stage::rectify), stages_->rectifiers->left.working_set_bytes() +
                                         stages_->rectifiers->right.working_set_bytes() + images);
  }
  report.add(name(Stage::corners), stages_->corners_left.working_set_bytes() +
                                       stages_->corners_right.working_set_bytes());
  report.add(name(Stage::disparity), stages_->matcher->working_set_bytes() +
                                         (obstacles_ ? obstacles_->working_set_bytes() : 0) +
                                         (depth_grid_ ? depth_grid_->working_set_bytes() : 0));
  report.add(name(Stage::sparse),
             stages_->sparse.working_set_bytes() + points_.capacity() * sizeof(SparsePoint) +
                 point_order_.capacity() * sizeof(std::uint32_t) +
                 rectified_matches_.capacity() * sizeof(calib::RectifiedMatch) +
                 calibration_health_.working_set_bytes());
  if (detector_) {
    report.add(name(Stage::detect),
               detector_->working_set_bytes() + depths_.capacity() * sizeof(DetectionDepth));
  }
}

bool Pipeline::PairAhead::matches(GrayView left, GrayView right, std::uint32_t frame) const {
  const auto same = [](GrayView a, GrayView b) {
    return a.data() == b.data() && a.width() == b.width() && a.height() == b.height() &&
           a.stride() == b.stride();
  };
  return ready && images.frame == frame && same(images.left, left) && same(images.right, right);
}

// Task `task` of 2 x threads rectifying a pair into `slot`: one row band of one image (even
// tasks the left, odd the right), as many bands per image as there are workers.
void Pipeline::rectify_band(GrayView left_raw, GrayView right_raw, int slot, int task) {
  StereoRectifiers& rectifiers = *stages_->rectifiers;
  const auto s = static_cast<std::size_t>(slot);
  const int bands = pool_->threads();
  const int band = task / 2;
  const int height = rectified_left_[s].height();
  const int first = band * height / bands;
  const int end = (band + 1) * height / bands;
  if (task % 2 == 0) {
    rectifiers.left.rectify_rows(left_raw, rectified_left_[s].view(), first, end);
  } else {
    rectifiers.right.rectify_rows(right_raw, rectified_right_[s].view(), first, end);
  }
}

// The stages of a pair on the one pool: the rectification of both images first, in row bands
// (every other stage reads it), unless it was done ahead; then one batch of tasks in the order
// they should start: the corners of both images, the disparity's stripes, the sparse matching
// (once the corners are there), the disparity's end (speckles, obstacles), the cascade's pyramid
// levels (largest first, so the small ones fill the workers' last gaps), and last the next pair's
// rectification (in the gaps that are left). The detections' depths join after all.
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
  const auto time_of = [&r](Stage s) -> hal::Nanoseconds& {
    return r.times[static_cast<std::size_t>(s)];
  };

  const bool rectify = protocol::has_stage(run, Stage::rectify);
  const bool was_ahead = ahead_.matches(left, right, frame);
  ahead_.ready = false;
  if (rectify && was_ahead) {
    slot_ = ahead_.slot;
    r.left = rectified_left_[static_cast<std::size_t>(slot_)].view();
    r.right = rectified_right_[static_cast<std::size_t>(slot_)].view();
    time_of(Stage::rectify) = ahead_.rectify_ns;
    ++ahead_used_;
  } else if (rectify) {
    const hal::Nanoseconds start = steady_now();
    pool_->run(2 * pool_->threads(),
               [&](int task, int) { rectify_band(left, right, slot_, task); });
    r.left = rectified_left_[static_cast<std::size_t>(slot_)].view();
    r.right = rectified_right_[static_cast<std::size_t>(slot_)].view();
    time_of(Stage::rectify) = steady_now() - start;
  }
  r.stages = run & (stage_bit(Stage::capture) | stage_bit(Stage::rectify));

  // What cannot start (an image of the wrong size) throws here, before a task is queued.
  const bool disparity = protocol::has_stage(run, Stage::disparity);
  if (disparity && !disparity_ran_last_) stages_->matcher->reset_history();
  disparity_ran_last_ = false;  // stays so if start() throws: that pair had no disparity
  const int stripes = disparity ? stages_->matcher->start(r.left, r.right) : 0;
  disparity_ran_last_ = disparity;
  const int levels = protocol::has_stage(run, Stage::detect) ? detector_->start(r.left) : 0;
  auto corners = [&](int image, int) {
    if (image == 0) {
      r.corners_left = stages_->corners_left.detect(r.left);
    } else {
      r.corners_right = stages_->corners_right.detect(r.right);
    }
  };
  // The stripe that ends last ends the disparity too (speckles, obstacles): no worker waits.
  std::atomic<int> stripes_left{stripes};
  auto stripe = [&](int i, int worker) {
    stages_->matcher->run_stripe(i, worker);
    if (stripes_left.fetch_sub(1, std::memory_order_acq_rel) == 1) finish_dense(r);
  };
  auto sparse = [&](int, int) { match_sparse(r); };
  auto level = [&](int i, int worker) { detector_->search_level(i, worker); };
  // The next pair, when it is there and of the images' size (one that is not is rectified, and
  // refused, when it is processed itself), into the other slot, in as many row bands per image as
  // there are workers. It counts as rectified ahead only once the whole batch has run.
  const int ahead_slot = 1 - slot_;
  bool took_next = false;
  auto take_next = [&](int, int) {
    const std::optional<NextPair::Images> images = next->take();
    const auto fits = [&](GrayView image) {
      return image.width() == left.width() && image.height() == left.height();
    };
    if (images && fits(images->left) && fits(images->right)) {
      ahead_.images = *images;
      took_next = true;
    }
  };
  auto rectify_next = [&](int task, int) {
    if (took_next) rectify_band(ahead_.images.left, ahead_.images.right, ahead_slot, task);
  };
  TaskBatch& batch = batch_;
  batch.clear();
  int corners_part = TaskBatch::kNoPart;
  int stripes_part = TaskBatch::kNoPart;
  int sparse_part = TaskBatch::kNoPart;
  int levels_part = TaskBatch::kNoPart;
  int ahead_part = TaskBatch::kNoPart;
  if (protocol::has_stage(run, Stage::corners)) corners_part = batch.add(2, corners);
  if (protocol::has_stage(run, Stage::disparity)) stripes_part = batch.add(stripes, stripe);
  if (protocol::has_stage(run, Stage::sparse)) sparse_part = batch.add(1, sparse, corners_part);
  if (protocol::has_stage(run, Stage::detect)) levels_part = batch.add(levels, level);
  if (next != nullptr && rectify) {
    ahead_part = batch.add(2 * pool_->threads(), rectify_next, batch.add(1, take_next));
  }
  batch.run(*pool_);
  time_of(Stage::corners) = batch.span_ns(corners_part, corners_part);
  time_of(Stage::disparity) = batch.span_ns(stripes_part, stripes_part);
  time_of(Stage::sparse) = batch.span_ns(sparse_part, sparse_part);
  if (took_next) {
    ahead_.slot = ahead_slot;
    ahead_.rectify_ns = batch.span_ns(ahead_part, ahead_part);
    ahead_.ready = true;
    ++ahead_rectified_;
  }
  if (protocol::has_stage(run, Stage::detect)) {
    const hal::Nanoseconds start = steady_now();
    r.detections = detector_->finish();
    attach_depths(r);
    time_of(Stage::detect) = batch.span_ns(levels_part, levels_part) + (steady_now() - start);
  }
  r.stages = run;
  return r;
}

void Pipeline::finish_dense(FrameResult& r) {
  r.disparity = stages_->matcher->finish();
  std::uint64_t valid = 0;
  for (int y = 0; y < r.disparity.height(); ++y) {
    const std::int16_t* row = r.disparity.row(y);
    for (int x = 0; x < r.disparity.width(); ++x) valid += row[x] >= 0 ? 1 : 0;
  }
  r.valid_disparity_permille = static_cast<int>(
      valid * 1000 / (static_cast<std::uint64_t>(r.disparity.width()) * r.disparity.height()));
  if (obstacles_) {
    r.obstacles = &obstacles_->measure(r.disparity, r.frame, stages_->matcher->confidence());
  }
  if (depth_grid_) {
    r.depth_grid = &depth_grid_->measure(r.disparity, r.frame, stages_->matcher->confidence());
  }
}

void Pipeline::match_sparse(FrameResult& r) {
  r.matches = stages_->sparse.match(r.left, r.corners_left, r.right, r.corners_right);
  if (triangulator_) {
    const std::size_t n = triangulate_matches(*triangulator_, r.matches, points_);
    r.points = {points_.data(), n};
    // The most distinctive matches (smallest descriptor distance) become the points sent.
    for (std::size_t i = 0; i < n; ++i) point_order_[i] = static_cast<std::uint32_t>(i);
    const std::size_t keep = std::min(n, static_cast<std::size_t>(max_points_));
    const auto distance = [&](std::uint32_t i) { return points_[i].distance; };
    std::partial_sort(point_order_.begin(),
                      point_order_.begin() + static_cast<std::ptrdiff_t>(keep),
                      point_order_.begin() + static_cast<std::ptrdiff_t>(n),
                      [&](std::uint32_t a, std::uint32_t b) {
                        return distance(a) != distance(b) ? distance(a) < distance(b) : a < b;
                      });
    r.best_points = {point_order_.data(), keep};
  }
  if (protocol::has_stage(r.stages, Stage::rectify)) {
    for (std::size_t i = 0; i < r.matches.size(); ++i) {
      const vision::SparseMatch& m = r.matches[i];
      rectified_matches_[i] = {m.xl, m.yl, m.xr, m.yr};
    }
    r.calibration_health =
        calibration_health_.measure({rectified_matches_.data(), r.matches.size()});
  }
}

void Pipeline::attach_depths(FrameResult& r) {
  for (std::size_t i = 0; i < r.detections.size(); ++i) {
    depths_[i] = depth_estimator_ && !r.disparity.empty()
                     ? depth_estimator_->estimate(r.detections[i], r.disparity)
                     : DetectionDepth{};
  }
  r.detection_depths = {depths_.data(), r.detections.size()};
}

}  // namespace epipole::firmware
