#include <gtest/gtest.h>

#include "allocation_counter.hpp"
#include "epipole/vision/harris.hpp"
#include "random_image.hpp"

namespace epipole::vision {
namespace {

TEST(HarrisAllocations, DetectNeverAllocates) {
  for (const SimdPath path : available_simd_paths()) {
    GrayImage image(320, 240);
    test::fill(image.view(), test::Pattern::blobs, 11);
    HarrisConfig config{.width = 320,
                        .height = 240,
                        .block_size = 5,
                        .min_distance = 5,
                        .max_corners = 30};  // small, so the bounded-output path runs too
    HarrisDetector detector(config, path);
    std::size_t corners = 0;
    test::AllocationCounter counter;
    for (int i = 0; i < 100; ++i) corners += detector.detect(image.view()).size();
    EXPECT_EQ(counter.count(), 0u) << to_string(path);
    EXPECT_EQ(corners, 100u * 30u) << "the image should have more corners than the bound";
    EXPECT_TRUE(detector.truncated());
  }
}

}  // namespace
}  // namespace epipole::vision
