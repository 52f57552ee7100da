// Corners: FAST or Harris, as the board says, on both images (one task each).
#include <variant>

#include "epipole/vision/fast.hpp"
#include "epipole/vision/harris.hpp"
#include "stage_files.hpp"

namespace epipole::firmware::stages {

namespace {

// One corner detector per image.
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

class CornersStage final : public PipelineStage {
 public:
  explicit CornersStage(const StageContext& c) : left_(c.board, c.path), right_(c.board, c.path) {}

  std::size_t working_set_bytes() const override {
    return left_.working_set_bytes() + right_.working_set_bytes();
  }
  int add_tasks(PairWork& work) override {
    result_ = &work.result;
    return work.batch.add(2, task_);
  }

 private:
  struct Task {
    CornersStage& s;
    void operator()(int image, int) const {
      FrameResult& r = *s.result_;
      if (image == 0) {
        r.corners_left = s.left_.detect(r.left);
      } else {
        r.corners_right = s.right_.detect(r.right);
      }
    }
  };
  CornerDetector left_, right_;
  FrameResult* result_ = nullptr;
  Task task_{*this};
};

}  // namespace

extern constinit const StageDefinition corners_stage{make_stage<CornersStage>};

}  // namespace epipole::firmware::stages
