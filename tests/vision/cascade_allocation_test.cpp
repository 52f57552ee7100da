#include <gtest/gtest.h>

#include "allocation_counter.hpp"
#include "cascade_test_models.hpp"
#include "epipole/vision/box_disparity.hpp"
#include "epipole/vision/cascade.hpp"
#include "random_image.hpp"

namespace epipole::vision {
namespace {

// Every path, Haar (with tilted features, so every plane is used) and LBP, grouped and raw:
// detect() allocates nothing over 100 images, including images smaller than the configured size.
TEST(CascadeAllocations, DetectNeverAllocates) {
  for (const CascadeFeatureType type : {CascadeFeatureType::haar, CascadeFeatureType::lbp}) {
    test::RandomCascadeShape shape;
    shape.type = type;
    shape.tilted = true;
    const CascadeModel model(test::random_cascade(shape, 3), "random");
    GrayImage image(160, 120);
    test::fill(image.view(), test::Pattern::blobs, 11);
    for (const SimdPath path : available_simd_paths()) {
      CascadeConfig config;
      config.max_width = 160;
      config.max_height = 120;
      config.min_neighbors = 1;
      config.max_raw_hits = 300;  // small, so that the bounded path runs too
      CascadeDetector detector(model, config, path);
      std::size_t boxes = 0;
      std::size_t raw = 0;
      test::AllocationCounter counter;
      for (int i = 0; i < 100; ++i) {
        const GrayView view = i % 3 == 2 ? GrayView(image.view().sub(0, 0, 131, 97)) : image.view();
        boxes += detector.detect(view).size();
        raw += detector.raw_hits().size();
      }
      EXPECT_EQ(counter.count(), 0u) << to_string(path);
      EXPECT_GT(raw, 100u) << "windows must pass for the test to mean something";
      EXPECT_GT(boxes, 0u);
    }
  }
}

TEST(CascadeAllocations, BoxDisparityNeverAllocates) {
  Image<std::int16_t> disparity(160, 120);
  for (int y = 0; y < 120; ++y) {
    for (int x = 0; x < 160; ++x) disparity(x, y) = static_cast<std::int16_t>((x * 31 + y) % 1000);
  }
  BoxDisparity median(64);
  long sum = 0;
  test::AllocationCounter counter;
  for (int i = 0; i < 100; ++i)
    sum += median.median(disparity.view(), i, i / 2, 40, 30).value_or(0);
  EXPECT_EQ(counter.count(), 0u);
  EXPECT_GT(sum, 0);
}

}  // namespace
}  // namespace epipole::vision
