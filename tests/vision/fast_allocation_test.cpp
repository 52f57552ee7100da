#include <gtest/gtest.h>

#include "allocation_counter.hpp"
#include "epipole/vision/fast.hpp"
#include "random_image.hpp"

namespace epipole::vision {
namespace {

TEST(FastAllocations, CounterSeesAllocations) {
  test::AllocationCounter counter;
  auto p = std::make_unique<int>(7);
  EXPECT_EQ(counter.count(), 1u)
      << "the counter must see a plain new, or the test below proves nothing";
}

TEST(FastAllocations, DetectNeverAllocates) {
  for (const SimdPath path : available_simd_paths()) {
    GrayImage image(320, 240);
    test::fill(image.view(), test::Pattern::blobs, 11);
    FastConfig config{.width = 320,
                      .height = 240,
                      .threshold = 20,
                      .nonmax = true,
                      .max_corners = 50};  // small, so the bounded-output path runs too
    FastDetector detector(config, path);
    std::size_t corners = 0;
    test::AllocationCounter counter;
    for (int i = 0; i < 100; ++i) corners += detector.detect(image.view()).size();
    EXPECT_EQ(counter.count(), 0u) << to_string(path);
    EXPECT_EQ(corners, 100u * 50u) << "the image should have more corners than the bound";
    EXPECT_TRUE(detector.truncated());
  }
}

}  // namespace
}  // namespace epipole::vision
