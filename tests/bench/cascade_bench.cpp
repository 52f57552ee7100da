#include <benchmark/benchmark.h>

#include <map>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <opencv2/objdetect.hpp>
#include <stdexcept>
#include <string>
#include <utility>

#include "epipole/tools/cascade_xml.hpp"
#include "epipole/vision/cascade.hpp"
#include "test_data.hpp"

namespace epipole::bench {
namespace {

// The design brief's settings: scale 1.1, minNeighbors 3, minSize 30.
constexpr double kScale = 1.1;
constexpr int kMinNeighbors = 3;
constexpr int kMinSize = 30;

const char* cascade_file(int cascade) {
  return cascade == 0 ? "cascades/haarcascades/haarcascade_frontalface_default.xml"
                      : "cascades/lbpcascades/lbpcascade_frontalface_improved.xml";
}

// messi5 (548x342) gray, or resized (INTER_LINEAR) to another size.
const cv::Mat& messi(int width, int height) {
  static std::map<std::pair<int, int>, cv::Mat> cache;
  cv::Mat& image = cache[{width, height}];
  if (image.empty()) {
    const cv::Mat full =
        cv::imread(test::data_file("samples/messi5.jpg").string(), cv::IMREAD_GRAYSCALE);
    if (full.empty()) throw std::runtime_error("cannot read messi5.jpg");
    if (full.cols == width && full.rows == height) {
      image = full;
    } else {
      cv::resize(full, image, cv::Size(width, height), 0, 0, cv::INTER_LINEAR);
    }
  }
  return image;
}

void sizes(benchmark::internal::Benchmark* benchmark) {
  benchmark->Args({548, 342})->Args({640, 480})->Unit(benchmark::kMillisecond);
}

void cascade_ours(benchmark::State& state, int cascade, SimdPath path) {
  if (!simd_path_available(path)) {
    state.SkipWithError("this CPU cannot run this kernel path");
    return;
  }
  const cv::Mat& image = messi(static_cast<int>(state.range(0)), static_cast<int>(state.range(1)));
  const vision::CascadeModel model = tools::load_cascade(test::data_file(cascade_file(cascade)));
  vision::CascadeConfig config;
  config.max_width = image.cols;
  config.max_height = image.rows;
  config.scale_factor = kScale;
  config.min_neighbors = kMinNeighbors;
  config.min_object_width = config.min_object_height = kMinSize;
  vision::CascadeDetector detector(model, config, path);
  const GrayView view(image.ptr<std::uint8_t>(), image.cols, image.rows,
                      static_cast<std::ptrdiff_t>(image.step1()));
  std::size_t faces = 0;
  for (auto _ : state) {
    faces = detector.detect(view).size();
    benchmark::DoNotOptimize(faces);
  }
  state.counters["faces"] = static_cast<double>(faces);
  state.counters["raw"] = static_cast<double>(detector.raw_hits().size());
}

void cascade_opencv(benchmark::State& state, int cascade) {
  const cv::Mat& image = messi(static_cast<int>(state.range(0)), static_cast<int>(state.range(1)));
  cv::CascadeClassifier classifier(test::data_file(cascade_file(cascade)).string());
  std::vector<cv::Rect> faces;
  for (auto _ : state) {
    classifier.detectMultiScale(image, faces, kScale, kMinNeighbors, 0,
                                cv::Size(kMinSize, kMinSize));
    benchmark::DoNotOptimize(faces.data());
  }
  state.counters["faces"] = static_cast<double>(faces.size());
}

BENCHMARK_CAPTURE(cascade_ours, ref, 0, SimdPath::reference)->Name("haar_faces/ref")->Apply(sizes);
BENCHMARK_CAPTURE(cascade_ours, neon, 0, SimdPath::neon)->Name("haar_faces/neon")->Apply(sizes);
BENCHMARK_CAPTURE(cascade_ours, avx2, 0, SimdPath::avx2)->Name("haar_faces/avx2")->Apply(sizes);
BENCHMARK_CAPTURE(cascade_opencv, opencv, 0)->Name("haar_faces/opencv")->Apply(sizes);
BENCHMARK_CAPTURE(cascade_ours, ref, 1, SimdPath::reference)->Name("lbp_faces/ref")->Apply(sizes);
BENCHMARK_CAPTURE(cascade_ours, neon, 1, SimdPath::neon)->Name("lbp_faces/neon")->Apply(sizes);
BENCHMARK_CAPTURE(cascade_ours, avx2, 1, SimdPath::avx2)->Name("lbp_faces/avx2")->Apply(sizes);
BENCHMARK_CAPTURE(cascade_opencv, opencv, 1)->Name("lbp_faces/opencv")->Apply(sizes);

}  // namespace
}  // namespace epipole::bench
