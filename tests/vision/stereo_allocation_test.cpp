// Fixed memory: after construction, neither the matcher nor its thread pool allocates per frame.
#include <gtest/gtest.h>

#include "allocation_counter.hpp"
#include "epipole/core/thread_pool.hpp"
#include "epipole/vision/stereo.hpp"
#include "random_image.hpp"

namespace epipole::vision {
namespace {

TEST(StereoAllocations, CounterSeesAllocations) {
  test::AllocationCounter counter;
  auto p = std::make_unique<int>(7);
  EXPECT_EQ(counter.count(), 1u)
      << "the counter must see a plain new, or the tests below prove nothing";
}

TEST(StereoAllocations, ThreadPoolRunNeverAllocates) {
  ThreadPool pool(2);
  int a = 0;
  int b = 0;
  test::AllocationCounter counter;
  for (int i = 0; i < 100; ++i) {
    pool.run(2, [&](int task, int) { (task == 0 ? a : b) += 1; });
  }
  EXPECT_EQ(counter.count(), 0u);
  EXPECT_EQ(a + b, 200);
}

TEST(StereoAllocations, ComputeNeverAllocates) {
  GrayImage left(96, 40), right(96, 40);
  test::fill(left.view(), test::Pattern::blobs, 1);
  test::fill(right.view(), test::Pattern::blobs, 2);
  for (const SimdPath path : available_simd_paths()) {
    for (const StereoMethod method : {StereoMethod::sgm, StereoMethod::bm}) {
      for (const int threads : {1, 2}) {
        StereoConfig config{.width = 96, .height = 40, .max_disparity = 32};
        config.method = method;
        config.threads = threads;
        StereoMatcher matcher(config, path);
        test::AllocationCounter counter;
        for (int i = 0; i < 3; ++i) matcher.compute(left.view(), right.view());
        EXPECT_EQ(counter.count(), 0u) << to_string(path) << " threads " << threads;
      }
    }
  }
}

// The bytes the documentation states for 640x480 (docs/vision.md).
TEST(StereoAllocations, WorkingSetAt640x480) {
  for (const int d : {64, 128}) {
    StereoConfig config{.width = 640, .height = 480, .max_disparity = d};
    const StereoMatcher sgm(config);
    config.method = StereoMethod::bm;
    const StereoMatcher bm(config);
    std::printf("640x480, %d disparities: sgm %zu bytes, bm %zu bytes\n", d,
                sgm.working_set_bytes(), bm.working_set_bytes());
    EXPECT_LT(sgm.working_set_bytes(), d == 64 ? 2'400'000u : 2'800'000u);
  }
}

}  // namespace
}  // namespace epipole::vision
