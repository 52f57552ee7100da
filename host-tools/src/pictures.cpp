#include "pictures.hpp"

#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <string>

#include "epipole/core/error.hpp"
#include "epipole/vision/stereo.hpp"

namespace epipole::tools {

namespace {

constexpr int kFont = cv::FONT_HERSHEY_SIMPLEX;
constexpr double kFontScale = 0.45;
constexpr int kLabelPadding = 2;

// TURBO, indexed by t * 255, in R, G, B order (applyColorMap writes B, G, R).
const std::array<cv::Vec3b, 256>& turbo() {
  static const std::array<cv::Vec3b, 256> table = [] {
    cv::Mat ramp(1, 256, CV_8UC1);
    for (int i = 0; i < 256; ++i) ramp.at<std::uint8_t>(i) = static_cast<std::uint8_t>(i);
    cv::Mat bgr;
    cv::applyColorMap(ramp, bgr, cv::COLORMAP_TURBO);
    cv::cvtColor(bgr, bgr, cv::COLOR_BGR2RGB);
    std::array<cv::Vec3b, 256> rgb;
    for (int i = 0; i < 256; ++i) rgb[static_cast<std::size_t>(i)] = bgr.at<cv::Vec3b>(i);
    return rgb;
  }();
  return table;
}

cv::Size text_size(const std::string& text, int* baseline = nullptr) {
  int ignored = 0;
  return cv::getTextSize(text, kFont, kFontScale, 1, baseline != nullptr ? baseline : &ignored);
}

// Text whose top-left corner is `top_left`, without a box (the legend's black background).
void draw_text(cv::Mat& picture, cv::Point top_left, const std::string& text, cv::Scalar colour) {
  cv::putText(picture, text, top_left + cv::Point(0, text_size(text).height), kFont, kFontScale,
              colour, 1, cv::LINE_AA);
}

}  // namespace

RgbImage rgb_picture(GrayView gray) {
  RgbImage picture(gray.width(), gray.height());
  cv::Mat out = mat_of(picture.view());
  cv::cvtColor(mat_of(gray), out, cv::COLOR_GRAY2RGB);
  return picture;
}

RgbImage side_by_side(GrayView left, GrayView right) {
  require(left.height() == right.height(), "side by side: heights ", left.height(), " and ",
          right.height(), " differ");
  RgbImage picture(left.width() + right.width(), left.height());
  const cv::Mat all = mat_of(picture.view());
  cv::Mat left_part = all.colRange(0, left.width());  // cvtColor writes into these
  cv::Mat right_part = all.colRange(left.width(), all.cols);
  cv::cvtColor(mat_of(left), left_part, cv::COLOR_GRAY2RGB);
  cv::cvtColor(mat_of(right), right_part, cv::COLOR_GRAY2RGB);
  return picture;
}

cv::Scalar colour_of(double t) {
  const int index = static_cast<int>(std::lround(std::clamp(t, 0.0, 1.0) * 255.0));
  const cv::Vec3b c = turbo()[static_cast<std::size_t>(index)];
  return {static_cast<double>(c[0]), static_cast<double>(c[1]), static_cast<double>(c[2])};
}

int label_height() {
  const int text = text_size("0").height;
  return text + text / 2 + 2 * kLabelPadding;
}

void draw_label(cv::Mat& picture, cv::Point top_left, const std::string& text, cv::Scalar colour) {
  int baseline = 0;
  const cv::Size size = text_size(text, &baseline);
  const cv::Size box(size.width + 2 * kLabelPadding, size.height + baseline + 2 * kLabelPadding);
  top_left.x = std::clamp(top_left.x, 0, std::max(0, picture.cols - box.width));
  top_left.y = std::clamp(top_left.y, 0, std::max(0, picture.rows - box.height));
  cv::rectangle(picture, cv::Rect(top_left, box), cv::Scalar::all(0), cv::FILLED);
  draw_text(picture, top_left + cv::Point(kLabelPadding, kLabelPadding), text, colour);
}

RgbImage disparity_picture(ImageView<const std::int16_t> disparity, int max_disparity) {
  const int width = disparity.width();
  const int height = disparity.height();
  RgbImage picture(width, height + kLegendHeight);
  cv::Mat all = mat_of(picture.view());
  all.setTo(cv::Scalar::all(0));

  // The map: disparity 0..max_disparity onto TURBO's 256 colours; invalid pixels stay black.
  const cv::Mat d16 = mat_of(disparity);
  cv::Mat index;
  d16.convertTo(index, CV_8U, 255.0 / (16.0 * max_disparity));
  cv::Mat bgr;
  cv::applyColorMap(index, bgr, cv::COLORMAP_TURBO);
  cv::Mat image = all.rowRange(0, height);
  cv::cvtColor(bgr, image, cv::COLOR_BGR2RGB);
  image.setTo(cv::Scalar::all(0), d16 == vision::kInvalidDisparity);

  // The legend: "disparity, px" then the colour bar with five labelled ticks.
  const cv::Scalar white = cv::Scalar::all(255);
  const int margin = 8;
  const int top = height + 5;
  const std::string title = "disparity, px";
  draw_text(all, {margin, top + 1}, title, white);
  const int bar_left = std::min(width - 1, 2 * margin + text_size(title).width);
  const int bar_width = std::max(1, width - margin - bar_left);
  for (int i = 0; i < bar_width; ++i) {
    const cv::Scalar c = colour_of(static_cast<double>(i) / std::max(1, bar_width - 1));
    cv::line(all, {bar_left + i, top}, {bar_left + i, top + 11}, c);
  }
  constexpr int kTicks = 4;
  for (int t = 0; t <= kTicks; ++t) {
    const std::string label = std::to_string(max_disparity * t / kTicks);
    const int x = bar_left + (bar_width - 1) * t / kTicks;
    cv::line(all, {x, top + 12}, {x, top + 15}, white);
    const int label_width = text_size(label).width;
    const int label_x = std::clamp(x - label_width / 2, 0, std::max(0, width - label_width));
    draw_text(all, {label_x, top + 19}, label, white);
  }
  return picture;
}

}  // namespace epipole::tools
