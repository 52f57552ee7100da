#include <benchmark/benchmark.h>

#include <opencv2/calib3d.hpp>
#include <opencv2/imgproc.hpp>

#include "bench_images.hpp"
#include "epipole/vision/remap.hpp"

namespace epipole::bench {
namespace {

// A realistic rectification map for a width x height camera: the data set's intrinsics
// scaled to the size, its distortion, and a rotation of about 1.5 degrees.
struct Maps {
  cv::Mat xy;        // CV_16SC2
  cv::Mat fraction;  // CV_16UC1
};

Maps rectification_maps(int width, int height) {
  const double sx = width / 640.0, sy = height / 480.0;
  const cv::Matx33d k(534.0 * sx, 0, 342.0 * sx, 0, 534.0 * sy, 235.0 * sy, 0, 0, 1);
  const cv::Vec<double, 5> distortion(-0.28, 0.09, 0.001, -0.0003, 0.0);
  cv::Matx33d rotation;
  cv::Rodrigues(cv::Vec3d(0.012, -0.02, 0.008), rotation);
  Maps maps;
  cv::initUndistortRectifyMap(k, distortion, rotation, k, cv::Size(width, height), CV_16SC2,
                              maps.xy, maps.fraction);
  return maps;
}

void remap_ours(benchmark::State& state, SimdPath path) {
  if (!simd_path_available(path)) {
    state.SkipWithError("this CPU cannot run this kernel path");
    return;
  }
  const int width = static_cast<int>(state.range(0));
  const int height = static_cast<int>(state.range(1));
  const cv::Mat& image = aloe_left(width, height);
  const Maps maps = rectification_maps(width, height);
  vision::RemapMap map(
      ImageView<const std::int16_t>(maps.xy.ptr<std::int16_t>(), 2 * width, height,
                                    static_cast<std::ptrdiff_t>(maps.xy.step1())),
      ImageView<const std::uint16_t>(maps.fraction.ptr<std::uint16_t>(), width, height,
                                     static_cast<std::ptrdiff_t>(maps.fraction.step1())));
  vision::Rectifier rectifier(
      {.source_width = width, .source_height = height, .width = width, .height = height},
      std::move(map), path);
  const GrayView source(image.ptr<std::uint8_t>(), width, height,
                        static_cast<std::ptrdiff_t>(image.step1()));
  for (auto _ : state) {
    benchmark::DoNotOptimize(rectifier.rectify(source).data());
    benchmark::ClobberMemory();
  }
}

void remap_opencv(benchmark::State& state) {
  const int width = static_cast<int>(state.range(0));
  const int height = static_cast<int>(state.range(1));
  const cv::Mat& image = aloe_left(width, height);
  const Maps maps = rectification_maps(width, height);
  cv::Mat output(height, width, CV_8UC1);
  for (auto _ : state) {
    cv::remap(image, output, maps.xy, maps.fraction, cv::INTER_LINEAR, cv::BORDER_CONSTANT);
    benchmark::DoNotOptimize(output.data);
    benchmark::ClobberMemory();
  }
}

BENCHMARK_CAPTURE(remap_ours, ref, SimdPath::reference)->Name("remap/ref")->Apply(frame_sizes);
BENCHMARK_CAPTURE(remap_ours, neon, SimdPath::neon)->Name("remap/neon")->Apply(frame_sizes);
BENCHMARK_CAPTURE(remap_ours, avx2, SimdPath::avx2)->Name("remap/avx2")->Apply(frame_sizes);
BENCHMARK(remap_opencv)->Name("remap/opencv")->Apply(frame_sizes);

}  // namespace
}  // namespace epipole::bench
