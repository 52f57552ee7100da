#include <gtest/gtest.h>

#include "allocation_counter.hpp"
#include "epipole/vision/remap.hpp"
#include "random_image.hpp"

namespace epipole::vision {
namespace {

TEST(RemapAllocations, RectifyNeverAllocates) {
  for (const SimdPath path : {SimdPath::reference, best_simd_path()}) {
    GrayImage image(320, 240);
    test::fill(image.view(), test::Pattern::blobs, 11);
    // A shifted, scaled map: inside blocks, border blocks and wholly outside blocks.
    RemapMap map(300, 260);
    for (int v = 0; v < 260; ++v)
      for (int u = 0; u < 300; ++u) {
        map.xy()(2 * u, v) = static_cast<std::int16_t>(u * 9 / 8 - 10);
        map.xy()(2 * u + 1, v) = static_cast<std::int16_t>(v - 12);
        map.fractions()(u, v) = static_cast<std::uint16_t>((u * 7 + v * 3) % 1024);
      }
    Rectifier rectifier({.source_width = 320, .source_height = 240, .width = 300, .height = 260},
                        std::move(map), path);
    GrayImage output(300, 260);
    unsigned checksum = 0;
    test::AllocationCounter counter;
    for (int i = 0; i < 100; ++i) {
      checksum += rectifier.rectify(image.view())(150, 130);
      rectifier.rectify(image.view(), output.view());
      checksum += output(10, 10);
    }
    EXPECT_EQ(counter.count(), 0u) << to_string(path);
    EXPECT_GT(checksum, 0u);
  }
}

}  // namespace
}  // namespace epipole::vision
