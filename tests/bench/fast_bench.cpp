#include <benchmark/benchmark.h>

#include <opencv2/features2d.hpp>

#include "bench_images.hpp"
#include "epipole/vision/fast.hpp"

namespace epipole::bench {
namespace {

constexpr int kThreshold = 20;

void fast_ours(benchmark::State& state, SimdPath path) {
  if (!simd_path_available(path)) {
    state.SkipWithError("this CPU cannot run this kernel path");
    return;
  }
  const cv::Mat& image =
      aloe_left(static_cast<int>(state.range(0)), static_cast<int>(state.range(1)));
  vision::FastDetector detector({.width = image.cols,
                                 .height = image.rows,
                                 .threshold = kThreshold,
                                 .nonmax = true,
                                 .max_corners = image.cols * image.rows},
                                path);
  const GrayView view(image.ptr<std::uint8_t>(), image.cols, image.rows,
                      static_cast<std::ptrdiff_t>(image.step1()));
  std::size_t corners = 0;
  for (auto _ : state) {
    corners = detector.detect(view).size();
    benchmark::DoNotOptimize(corners);
  }
  state.counters["corners"] = static_cast<double>(corners);
}

void fast_opencv(benchmark::State& state) {
  const cv::Mat& image =
      aloe_left(static_cast<int>(state.range(0)), static_cast<int>(state.range(1)));
  std::vector<cv::KeyPoint> keypoints;
  keypoints.reserve(static_cast<std::size_t>(image.total()));
  for (auto _ : state) {
    keypoints.clear();
    cv::FAST(image, keypoints, kThreshold, true);
    benchmark::DoNotOptimize(keypoints.data());
  }
  state.counters["corners"] = static_cast<double>(keypoints.size());
}

BENCHMARK_CAPTURE(fast_ours, ref, SimdPath::reference)->Name("fast_t20/ref")->Apply(frame_sizes);
BENCHMARK_CAPTURE(fast_ours, neon, SimdPath::neon)->Name("fast_t20/neon")->Apply(frame_sizes);
BENCHMARK_CAPTURE(fast_ours, avx2, SimdPath::avx2)->Name("fast_t20/avx2")->Apply(frame_sizes);
BENCHMARK(fast_opencv)->Name("fast_t20/opencv")->Apply(frame_sizes);

}  // namespace
}  // namespace epipole::bench
