#include "bench_images.hpp"

#include <benchmark/benchmark.h>

#include <map>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <stdexcept>
#include <utility>

#include "test_data.hpp"

namespace epipole::bench {

void frame_sizes(benchmark::internal::Benchmark* benchmark) {
  benchmark->Args({640, 480})->Args({1280, 720})->Unit(benchmark::kMillisecond);
}

const cv::Mat& aloe_left(int width, int height) {
  static std::map<std::pair<int, int>, cv::Mat> cache;
  cv::Mat& image = cache[{width, height}];
  if (image.empty()) {
    const cv::Mat full =
        cv::imread(test::data_file("samples/aloeL.jpg").string(), cv::IMREAD_GRAYSCALE);
    if (full.empty()) throw std::runtime_error("cannot read aloeL.jpg");
    cv::resize(full, image, cv::Size(width, height), 0, 0, cv::INTER_AREA);
  }
  return image;
}

}  // namespace epipole::bench
