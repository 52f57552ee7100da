// Detection: the Viola-Jones cascade's pyramid levels on the pool (largest first, so the small
// ones fill the workers' last gaps), then the detections and each one's depth from the
// disparity. A compiled cascade the board names that was not made yet leaves it off.
#include <system_error>
#include <vector>

#include "epipole/core/error.hpp"
#include "epipole/firmware/cascade_file.hpp"
#include "epipole/firmware/detection_depth.hpp"
#include "epipole/firmware/protocol/messages.hpp"
#include "epipole/vision/cascade.hpp"
#include "stage_files.hpp"
#include "steady_time.hpp"

namespace epipole::firmware::stages {

namespace {

using detail::steady_now;

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

class DetectStage final : public PipelineStage {
 public:
  // The detector, when the board has a cascade (or one is given) and detection is on.
  explicit DetectStage(const StageContext& c) {
    const BoardConfig& board = c.board;
    const bool named = protocol::has_stage(board.stages, protocol::Stage::detect) &&
                       !board.detector.cascade.empty();
    std::error_code ec;
    if (c.cascade == nullptr && named && board.detector.cascade.extension() != ".xml" &&
        !std::filesystem::exists(board.detector.cascade, ec)) {
      missing_ = board.detector.cascade;
      return;
    }
    if (c.cascade == nullptr && !named) return;
    const vision::CascadeModel model = c.cascade != nullptr ? *c.cascade : board_cascade(board);
    detector_ = std::make_unique<vision::CascadeDetector>(model, cascade_config(board), c.path);
    depths_.resize(static_cast<std::size_t>(protocol::kMaxDetections));
    if (c.triangulator != nullptr) {
      estimator_ =
          std::make_unique<DetectionDepthEstimator>(*c.triangulator, board.stereo.max_disparity);
    }
  }

  bool available() const override { return detector_ != nullptr; }
  std::filesystem::path missing_file() const override { return missing_; }
  std::size_t working_set_bytes() const override {
    return detector_ ? detector_->working_set_bytes() + depths_.capacity() * sizeof(DetectionDepth)
                     : 0;
  }
  void prepare(PairWork& work) override { levels_ = detector_->start(work.result.left); }
  int add_tasks(PairWork& work) override { return work.batch.add(levels_, level_); }
  void finish(PairWork& work) override {
    if (!protocol::has_stage(work.run, protocol::Stage::detect)) return;
    FrameResult& r = work.result;
    const hal::Nanoseconds start = steady_now();
    r.detections = detector_->finish();
    for (std::size_t i = 0; i < r.detections.size(); ++i) {
      depths_[i] = estimator_ && !r.disparity.empty()
                       ? estimator_->estimate(r.detections[i], r.disparity)
                       : DetectionDepth{};
    }
    r.detection_depths = {depths_.data(), r.detections.size()};
    r.times[static_cast<std::size_t>(protocol::Stage::detect)] += steady_now() - start;
  }

 private:
  struct Level {
    DetectStage& s;
    void operator()(int i, int worker) const { s.detector_->search_level(i, worker); }
  };

  std::unique_ptr<vision::CascadeDetector> detector_;
  std::filesystem::path missing_;
  std::unique_ptr<DetectionDepthEstimator> estimator_;
  std::vector<DetectionDepth> depths_;
  int levels_ = 0;
  Level level_{*this};
};

}  // namespace

extern constinit const StageDefinition detect_stage{make_stage<DetectStage>};

}  // namespace epipole::firmware::stages
