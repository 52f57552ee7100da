#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <vector>

#include "epipole/core/image.hpp"
#include "epipole/firmware/board_config.hpp"
#include "epipole/firmware/detection_depth.hpp"
#include "epipole/firmware/pipeline.hpp"
#include "epipole/firmware/sparse_points.hpp"
#include "epipole/vision/cascade.hpp"
#include "epipole/vision/corner.hpp"

namespace epipole::firmware::outputs {

// The parts of a pair's results an output keeps (PairCopy), as bits.
enum PairPart : unsigned {
  kRectified = 1u << 0,   // the rectified left and right images
  kRaw = 1u << 1,         // the images as captured
  kDisparity = 1u << 2,   // the dense disparity (x16)
  kPoints = 1u << 3,      // the sparse matches' 3-D points
  kDetections = 1u << 4,  // the detector's boxes and their depths
  kCorners = 1u << 5,     // the corners found in the left image
};
using PairParts = unsigned;

// When a pair was taken: the trigger edge on the board's clock, and the same instant on the
// system clock the robot's computers share (nanoseconds since the Unix epoch).
struct PairStamp {
  hal::Nanoseconds trigger_ns = 0;
  std::int64_t system_ns = 0;
};

// One pair's results as an output's thread reads them: copies of the parts the output asked for,
// in buffers allocated by the constructor for the board's image size and limits. copy_from()
// never allocates; the parts not asked for stay empty.
class PairCopy {
 public:
  PairCopy(const BoardConfig& board, PairParts parts);

  void copy_from(const FrameResult& result, const PairStamp& stamp);

  PairParts parts() const { return parts_; }
  std::size_t working_set_bytes() const;

  std::uint32_t frame = 0;
  PairStamp stamp;
  StageMask stages = 0;  // the stages that ran on it
  // Each is empty when the output did not ask for it, or the pair has none (its stage was off).
  bool has_rectified = false, has_raw = false, has_disparity = false;
  GrayImage left, right, left_raw, right_raw;
  Image<std::int16_t> disparity;  // x16, vision::kInvalidDisparity
  int valid_disparity_permille = 0;
  std::vector<SparsePoint> points;  // at most the board's sparse.max_matches
  std::vector<vision::Detection> detections;
  std::vector<DetectionDepth> detection_depths;  // one per detection
  std::vector<vision::Corner> corners;           // of the left image, at most corners.max_corners
  // The ground stage's result, whenever it ran (whatever the parts), and its plane when found.
  std::optional<protocol::Ground> ground;
  std::optional<GroundPlane> ground_plane;

 private:
  PairParts parts_;
};

}  // namespace epipole::firmware::outputs
