#include "opencv_pipeline.hpp"

#include <opencv2/features2d.hpp>
#include <opencv2/imgproc.hpp>

#include <chrono>
#include <vector>

#include "epipole/core/error.hpp"
#include "epipole/tools/opencv_matrices.hpp"

namespace epipole::tools {

namespace {

using protocol::Stage;
using protocol::stage_bit;

// The rectification maps OpenCV's users make: initUndistortRectifyMap, fixed point (CV_16SC2).
void rectification_maps(const calib::StereoCalibration& c, const calib::CameraCalibration& camera,
                        cv::Mat& map1, cv::Mat& map2) {
  cv::initUndistortRectifyMap(opencv_matrix(camera.camera_matrix()),
                              opencv_coefficients(camera.camera.distortion),
                              opencv_matrix(camera.rectification), opencv_matrix(camera.projection),
                              {c.width, c.height}, CV_16SC2, map1, map2);
}

cv::Ptr<cv::StereoMatcher> stereo_matcher(const vision::StereoConfig& s, bool sgbm_3way) {
  if (s.method == vision::StereoMethod::bm) {
    auto bm = cv::StereoBM::create(s.max_disparity, std::max(5, s.block_size | 1));
    bm->setUniquenessRatio(s.uniqueness);
    bm->setSpeckleWindowSize(s.speckle_size);
    bm->setSpeckleRange(s.speckle_range);
    bm->setDisp12MaxDiff(s.lr_max_diff);
    return bm;
  }
  constexpr int kBlock = 5;
  return cv::StereoSGBM::create(
      0, s.max_disparity, kBlock, 8 * kBlock * kBlock, 32 * kBlock * kBlock, s.lr_max_diff, 63,
      s.uniqueness, s.speckle_size, s.speckle_range,
      sgbm_3way ? cv::StereoSGBM::MODE_SGBM_3WAY : cv::StereoSGBM::MODE_SGBM);
}

}  // namespace

OpenCvPipeline::OpenCvPipeline(const firmware::BoardConfig& board,
                               const std::optional<calib::StereoCalibration>& calibration,
                               const std::filesystem::path& cascade_xml, bool sgbm_3way)
    : corners_(board.corners), detector_(board.detector) {
  const auto enabled = [&](Stage s) { return protocol::has_stage(board.stages, s); };
  if (enabled(Stage::rectify) && calibration) {
    rectification_maps(*calibration, calibration->left, map1_[0], map2_[0]);
    rectification_maps(*calibration, calibration->right, map1_[1], map2_[1]);
    stages_ |= stage_bit(Stage::rectify);
  }
  if (enabled(Stage::corners)) stages_ |= stage_bit(Stage::corners);
  if (enabled(Stage::disparity)) {
    matcher_ = stereo_matcher(board.stereo, sgbm_3way);
    stages_ |= stage_bit(Stage::disparity);
  }
  if (enabled(Stage::detect) && !cascade_xml.empty()) {
    require(cascade_.load(cascade_xml.string()), cascade_xml.string(),
            ": OpenCV's CascadeClassifier cannot read it");
    stages_ |= stage_bit(Stage::detect);
  }
}

OpenCvPipeline::Times OpenCvPipeline::process(const cv::Mat& left_raw, const cv::Mat& right_raw) {
  Times times{};
  auto start = std::chrono::steady_clock::now();
  const auto lap = [&](Stage s) {
    const auto now = std::chrono::steady_clock::now();
    times[static_cast<std::size_t>(s)] =
        std::chrono::duration<double, std::milli>(now - start).count();
    start = now;
  };
  const auto runs = [&](Stage s) { return protocol::has_stage(stages_, s); };
  // The inputs are never written: rectified images go to buffers of their own.
  cv::Mat left = left_raw;
  cv::Mat right = right_raw;
  if (runs(Stage::rectify)) {
    cv::remap(left_raw, rectified_[0], map1_[0], map2_[0], cv::INTER_LINEAR);
    cv::remap(right_raw, rectified_[1], map1_[1], map2_[1], cv::INTER_LINEAR);
    left = rectified_[0];
    right = rectified_[1];
    lap(Stage::rectify);
  }
  if (runs(Stage::corners)) {
    const auto& c = corners_;
    for (const cv::Mat* image : {&left, &right}) {
      std::vector<cv::KeyPoint> keypoints;
      std::vector<cv::Point2f> points;
      if (c.detector == firmware::BoardConfig::CornerDetector::fast) {
        cv::FAST(*image, keypoints, c.threshold, true);
      } else {
        cv::goodFeaturesToTrack(*image, points, c.max_corners, 0.01, 3, cv::noArray(), 3, true);
      }
    }
    lap(Stage::corners);
  }
  if (runs(Stage::disparity)) {
    cv::Mat disparity;
    matcher_->compute(left, right, disparity);
    lap(Stage::disparity);
  }
  if (runs(Stage::detect)) {
    const auto& d = detector_;
    std::vector<cv::Rect> objects;
    const cv::Size max_size = d.max_size > 0 ? cv::Size(d.max_size, d.max_size) : cv::Size();
    cascade_.detectMultiScale(left, objects, d.scale_factor, d.min_neighbors, 0,
                              {d.min_size, d.min_size}, max_size);
    lap(Stage::detect);
  }
  return times;
}

}  // namespace epipole::tools
