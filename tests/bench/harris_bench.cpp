#include <benchmark/benchmark.h>

#include <opencv2/imgproc.hpp>

#include "bench_images.hpp"
#include "epipole/vision/harris.hpp"

namespace epipole::bench {
namespace {

constexpr int kBlockSize = 3;
constexpr double kK = 0.04;

// The response map only: what cv::cornerHarris computes.
void harris_ours(benchmark::State& state, SimdPath path) {
  if (!simd_path_available(path)) {
    state.SkipWithError("this CPU cannot run this kernel path");
    return;
  }
  const cv::Mat& image =
      aloe_left(static_cast<int>(state.range(0)), static_cast<int>(state.range(1)));
  vision::HarrisDetector detector(
      {.width = image.cols, .height = image.rows, .block_size = kBlockSize, .k = kK}, path);
  const GrayView view(image.ptr<std::uint8_t>(), image.cols, image.rows,
                      static_cast<std::ptrdiff_t>(image.step1()));
  for (auto _ : state) {
    benchmark::DoNotOptimize(detector.compute_response(view).data());
    benchmark::ClobberMemory();
  }
}

void harris_opencv(benchmark::State& state) {
  const cv::Mat& image =
      aloe_left(static_cast<int>(state.range(0)), static_cast<int>(state.range(1)));
  cv::Mat response(image.size(), CV_32FC1);
  for (auto _ : state) {
    cv::cornerHarris(image, response, kBlockSize, 3, kK);
    benchmark::DoNotOptimize(response.data);
    benchmark::ClobberMemory();
  }
}

BENCHMARK_CAPTURE(harris_ours, ref, SimdPath::reference)
    ->Name("harris_response/ref")
    ->Apply(frame_sizes);
BENCHMARK_CAPTURE(harris_ours, neon, SimdPath::neon)
    ->Name("harris_response/neon")
    ->Apply(frame_sizes);
BENCHMARK_CAPTURE(harris_ours, avx2, SimdPath::avx2)
    ->Name("harris_response/avx2")
    ->Apply(frame_sizes);
BENCHMARK(harris_opencv)->Name("harris_response/opencv")->Apply(frame_sizes);

}  // namespace
}  // namespace epipole::bench
