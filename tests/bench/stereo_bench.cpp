// Dense disparity at 640x480 (Aloe resized with INTER_AREA), one thread unless the name says
// otherwise (the 2-thread runs report wall time and the process's CPU time): quality mode beside
// cv::StereoSGBM, fast mode beside cv::StereoBM, with the same disparity range. Arguments:
// width/height/disparities.
#include <benchmark/benchmark.h>

#include <opencv2/calib3d.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "bench_images.hpp"
#include "epipole/vision/stereo.hpp"
#include "test_data.hpp"

namespace epipole::bench {
namespace {

const cv::Mat& aloe_right(int width, int height) {
  static std::map<std::pair<int, int>, cv::Mat> cache;
  cv::Mat& image = cache[{width, height}];
  if (image.empty()) {
    const cv::Mat full =
        cv::imread(test::data_file("samples/aloeR.jpg").string(), cv::IMREAD_GRAYSCALE);
    if (full.empty()) throw std::runtime_error("cannot read aloeR.jpg");
    cv::resize(full, image, cv::Size(width, height), 0, 0, cv::INTER_AREA);
  }
  return image;
}

GrayView view(const cv::Mat& m) {
  return {m.ptr<std::uint8_t>(), m.cols, m.rows, static_cast<std::ptrdiff_t>(m.step1())};
}

void stereo_ours(benchmark::State& state, vision::StereoMethod method, SimdPath path, int threads) {
  if (!simd_path_available(path)) {
    state.SkipWithError("this CPU cannot run this kernel path");
    return;
  }
  const int w = static_cast<int>(state.range(0));
  const int h = static_cast<int>(state.range(1));
  const cv::Mat& left = aloe_left(w, h);
  const cv::Mat& right = aloe_right(w, h);
  vision::StereoConfig config{.width = w, .height = h};
  config.max_disparity = static_cast<int>(state.range(2));
  config.method = method;
  config.threads = threads;
  vision::StereoMatcher matcher(config, path);
  for (auto _ : state) {
    const auto d = matcher.compute(view(left), view(right));
    benchmark::DoNotOptimize(d.data());
  }
}

void sgbm_opencv(benchmark::State& state) {
  const int w = static_cast<int>(state.range(0));
  const int h = static_cast<int>(state.range(1));
  constexpr int kBlock = 5;
  const auto sgbm =
      cv::StereoSGBM::create(0, static_cast<int>(state.range(2)), kBlock, 8 * kBlock * kBlock,
                             32 * kBlock * kBlock, 1, 63, 10, 100, 2, cv::StereoSGBM::MODE_SGBM);
  cv::Mat out;
  for (auto _ : state) {
    sgbm->compute(aloe_left(w, h), aloe_right(w, h), out);
    benchmark::DoNotOptimize(out.data);
  }
}

void bm_opencv(benchmark::State& state) {
  const int w = static_cast<int>(state.range(0));
  const int h = static_cast<int>(state.range(1));
  const auto bm = cv::StereoBM::create(static_cast<int>(state.range(2)), 15);
  bm->setUniquenessRatio(10);
  bm->setSpeckleWindowSize(100);
  bm->setSpeckleRange(2);
  bm->setDisp12MaxDiff(1);
  cv::Mat out;
  for (auto _ : state) {
    bm->compute(aloe_left(w, h), aloe_right(w, h), out);
    benchmark::DoNotOptimize(out.data);
  }
}

void stereo_sizes(benchmark::internal::Benchmark* b) {
  b->Args({640, 480, 64})->Args({640, 480, 160})->Unit(benchmark::kMillisecond);
}

using vision::StereoMethod;
BENCHMARK_CAPTURE(stereo_ours, ref, StereoMethod::sgm, SimdPath::reference, 1)
    ->Name("stereo_sgm/ref")
    ->Apply(stereo_sizes);
BENCHMARK_CAPTURE(stereo_ours, neon, StereoMethod::sgm, SimdPath::neon, 1)
    ->Name("stereo_sgm/neon")
    ->Apply(stereo_sizes);
BENCHMARK_CAPTURE(stereo_ours, avx2, StereoMethod::sgm, SimdPath::avx2, 1)
    ->Name("stereo_sgm/avx2")
    ->Apply(stereo_sizes);
BENCHMARK_CAPTURE(stereo_ours, avx2_2threads, StereoMethod::sgm, SimdPath::avx2, 2)
    ->Name("stereo_sgm/avx2_2threads")
    ->Apply(stereo_sizes)
    ->MeasureProcessCPUTime()
    ->UseRealTime();
BENCHMARK_CAPTURE(stereo_ours, neon_2threads, StereoMethod::sgm, SimdPath::neon, 2)
    ->Name("stereo_sgm/neon_2threads")
    ->Apply(stereo_sizes)
    ->MeasureProcessCPUTime()
    ->UseRealTime();
BENCHMARK(sgbm_opencv)->Name("stereo_sgm/opencv")->Apply(stereo_sizes);
BENCHMARK_CAPTURE(stereo_ours, ref, StereoMethod::bm, SimdPath::reference, 1)
    ->Name("stereo_bm/ref")
    ->Apply(stereo_sizes);
BENCHMARK_CAPTURE(stereo_ours, neon, StereoMethod::bm, SimdPath::neon, 1)
    ->Name("stereo_bm/neon")
    ->Apply(stereo_sizes);
BENCHMARK_CAPTURE(stereo_ours, avx2, StereoMethod::bm, SimdPath::avx2, 1)
    ->Name("stereo_bm/avx2")
    ->Apply(stereo_sizes);
BENCHMARK_CAPTURE(stereo_ours, avx2_2threads, StereoMethod::bm, SimdPath::avx2, 2)
    ->Name("stereo_bm/avx2_2threads")
    ->Apply(stereo_sizes)
    ->MeasureProcessCPUTime()
    ->UseRealTime();
BENCHMARK_CAPTURE(stereo_ours, neon_2threads, StereoMethod::bm, SimdPath::neon, 2)
    ->Name("stereo_bm/neon_2threads")
    ->Apply(stereo_sizes)
    ->MeasureProcessCPUTime()
    ->UseRealTime();
BENCHMARK(bm_opencv)->Name("stereo_bm/opencv")->Apply(stereo_sizes);

}  // namespace
}  // namespace epipole::bench
