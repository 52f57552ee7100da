#include "delivery/pair_copy.hpp"

#include <algorithm>

#include "epipole/core/resident.hpp"
#include "epipole/firmware/protocol/messages.hpp"

namespace epipole::firmware::outputs {

namespace {

// Copies `from` into `to` when they have the same size (false: nothing copied).
template <typename T>
bool copy_image(ImageView<const T> from, Image<T>& to) {
  if (from.empty() || from.width() != to.width() || from.height() != to.height()) return false;
  for (int y = 0; y < from.height(); ++y) std::copy_n(from.row(y), from.width(), to.view().row(y));
  return true;
}

template <typename T>
void copy_within(std::span<const T> from, std::vector<T>& to) {
  to.assign(from.begin(),
            from.begin() + static_cast<std::ptrdiff_t>(std::min(from.size(), to.capacity())));
}

}  // namespace

PairCopy::PairCopy(const BoardConfig& board, PairParts parts) : parts_(parts) {
  const int w = board.width();
  const int h = board.height();
  if (parts & kRectified) {
    left = GrayImage(w, h);
    right = GrayImage(w, h);
  }
  if (parts & kRaw) {
    left_raw = GrayImage(w, h);
    right_raw = GrayImage(w, h);
  }
  if (parts & kDisparity) disparity = Image<std::int16_t>(w, h);
  if (parts & kPoints) {
    reserve_resident(points, static_cast<std::size_t>(board.sparse.max_matches));
  }
  if (parts & kDetections) {
    reserve_resident(detections, protocol::kMaxDetections);
    reserve_resident(detection_depths, protocol::kMaxDetections);
  }
  if (parts & kCorners) {
    reserve_resident(corners, static_cast<std::size_t>(board.corners.max_corners));
  }
}

void PairCopy::copy_from(const FrameResult& r, const PairStamp& pair_stamp) {
  frame = r.frame;
  stamp = pair_stamp;
  stages = r.stages;
  has_rectified = (parts_ & kRectified) && copy_image(r.left, left) && copy_image(r.right, right);
  has_raw =
      (parts_ & kRaw) && copy_image(r.left_raw, left_raw) && copy_image(r.right_raw, right_raw);
  has_disparity = (parts_ & kDisparity) && copy_image(r.disparity, disparity);
  valid_disparity_permille = r.valid_disparity_permille;
  if (parts_ & kPoints) copy_within(r.points, points);
  if (parts_ & kDetections) {
    copy_within(r.detections, detections);
    copy_within(r.detection_depths, detection_depths);
  }
  if (parts_ & kCorners) copy_within(r.corners_left, corners);
  ground.reset();
  if (r.ground != nullptr) ground = *r.ground;
  ground_plane.reset();
  if (r.ground_plane != nullptr) ground_plane = *r.ground_plane;
}

std::size_t PairCopy::working_set_bytes() const {
  return sizeof(PairCopy) + left.size_bytes() + right.size_bytes() + left_raw.size_bytes() +
         right_raw.size_bytes() + disparity.size_bytes() + points.capacity() * sizeof(SparsePoint) +
         detections.capacity() * sizeof(vision::Detection) +
         detection_depths.capacity() * sizeof(DetectionDepth) +
         corners.capacity() * sizeof(vision::Corner);
}

}  // namespace epipole::firmware::outputs
