// The firmware's side of the cascade: a compiled cascade file loaded with no XML library, and the
// depth of a detection from a disparity map and the sample calibration's Q (the median disparity
// in the box, through Triangulator::depth, equals f * B / d for the rig).
#include <gtest/gtest.h>

#include <cmath>

#include <fstream>

#include "cascade_test_models.hpp"
#include "epipole/firmware/cascade_file.hpp"
#include "epipole/firmware/detection_depth.hpp"
#include "epipole/vision/stereo.hpp"
#include "sample_calibration.hpp"

namespace epipole::firmware {
namespace {

TEST(CascadeFile, LoadsACompiledCascadeAndNamesBadFiles) {
  const vision::CascadeModel model(test::random_cascade({}, 8), "random");
  const std::vector<std::uint8_t> bytes = model.to_binary();
  const std::string file = ::testing::TempDir() + "epipole-firmware-cascade.bin";
  std::ofstream(file, std::ios::binary)
      .write(reinterpret_cast<const char*>(bytes.data()),
             static_cast<std::streamsize>(bytes.size()));
  EXPECT_EQ(load_compiled_cascade(file).data(), model.data());
  std::ofstream(file, std::ios::binary)
      .write(reinterpret_cast<const char*>(bytes.data()),
             static_cast<std::streamsize>(bytes.size() - 1));
  try {
    load_compiled_cascade(file);
    ADD_FAILURE() << "no error for a truncated file";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find(file + ": "), std::string::npos) << e.what();
  }
  EXPECT_THROW(load_compiled_cascade(file + ".missing"), Error);
}

TEST(DetectionDepth, MedianDisparityInTheBoxToMetres) {
  const calib::StereoCalibration calibration = test::sample_calibration();
  const calib::Triangulator triangulator(calibration);
  DetectionDepthEstimator estimator(triangulator, 64);
  Image<std::int16_t> disparity(calibration.width, calibration.height);
  for (int y = 0; y < disparity.height(); ++y) {
    for (int x = 0; x < disparity.width(); ++x) {
      // 20 px inside the box (a few pixels 20.5 or invalid), 5 px (far) elsewhere.
      const bool inside = x >= 200 && x < 300 && y >= 100 && y < 180;
      const int kind = (x * 7 + y * 13) % 10;
      disparity(x, y) = static_cast<std::int16_t>(!inside     ? 5 * 16
                                                  : kind == 0 ? vision::kInvalidDisparity
                                                  : kind == 1 ? 328
                                                              : 320);
    }
  }
  const vision::Detection face{200, 100, 100, 80, 5};
  const DetectionDepth d = estimator.estimate(face, disparity.view());
  ASSERT_TRUE(d.valid);
  EXPECT_EQ(d.disparity, 20.0f);
  // The rig: focal length 518.86 px (rectified), baseline |T| = 83.5 mm.
  const double focal = calibration.left.projection(0, 0);
  const double baseline = calibration.T.norm();
  EXPECT_NEAR(d.depth, focal * baseline / 20.0, 1e-4 * d.depth);
  EXPECT_NEAR(d.depth, 2.165, 0.001);

  // Several boxes at once; one wholly invalid, one half outside the image.
  Image<std::int16_t> invalid(calibration.width, calibration.height);
  for (int y = 0; y < invalid.height(); ++y) {
    for (int x = 0; x < invalid.width(); ++x) invalid(x, y) = vision::kInvalidDisparity;
  }
  EXPECT_FALSE(estimator.estimate(face, invalid.view()).valid);
  const vision::Detection boxes[] = {face, {600, 400, 100, 100, 3}, {250, 150, 10, 10, 4}};
  DetectionDepth out[3];
  estimator.estimate(boxes, disparity.view(), out);
  EXPECT_TRUE(out[0].valid);
  EXPECT_TRUE(out[1].valid);
  EXPECT_EQ(out[1].disparity, 5.0f);
  EXPECT_NEAR(out[1].depth, focal * baseline / 5.0, 1e-4 * out[1].depth);
  EXPECT_NEAR(out[2].depth, d.depth, 1e-9);
  DetectionDepth too_few[1];
  EXPECT_THROW(estimator.estimate(boxes, disparity.view(), too_few), Error);
}

TEST(DetectionDepth, ZeroDisparityHasNoDepth) {
  const calib::StereoCalibration calibration = test::sample_calibration();
  const calib::Triangulator triangulator(calibration);
  DetectionDepthEstimator estimator(triangulator, 64);
  Image<std::int16_t> disparity(64, 64);
  for (int y = 0; y < 64; ++y) {
    for (int x = 0; x < 64; ++x) disparity(x, y) = 0;
  }
  const DetectionDepth d = estimator.estimate({0, 0, 32, 32, 1}, disparity.view());
  EXPECT_FALSE(d.valid) << "a point at infinity";
  EXPECT_EQ(d.disparity, 0.0f);
}

}  // namespace
}  // namespace epipole::firmware
