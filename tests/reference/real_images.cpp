#include "real_images.hpp"

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <stdexcept>
#include <string>

#include "test_data.hpp"

namespace epipole::test {

std::vector<RealImage> corner_test_images() {
  std::vector<RealImage> images;
  images.push_back({"graf1", cv::imread(data_file("samples/graf1.png"), cv::IMREAD_GRAYSCALE)});
  cv::Mat aloe = cv::imread(data_file("samples/aloeL.jpg"), cv::IMREAD_GRAYSCALE);
  cv::Mat aloe_small;
  if (!aloe.empty()) cv::resize(aloe, aloe_small, cv::Size(640, 480), 0, 0, cv::INTER_AREA);
  images.push_back({"aloeL_640x480", aloe_small});
  images.push_back({"left01", cv::imread(data_file("samples/left01.jpg"), cv::IMREAD_GRAYSCALE)});
  for (const auto& image : images) {
    if (image.gray.empty()) throw std::runtime_error(std::string("cannot read ") + image.name);
  }
  return images;
}

}  // namespace epipole::test
