#pragma once

// Pictures for people (the host tool's --draw and --color, the simulation's pictures), drawn
// with OpenCV's imgproc on RGB images: colours are cv::Scalar(red, green, blue).

#include <opencv2/core.hpp>

#include <cstdint>
#include <string>

#include "epipole/core/image.hpp"
#include "epipole/tools/opencv_mat.hpp"

namespace epipole::tools {

// A gray image in colour, to draw on (mat_of(picture.view())).
RgbImage rgb_picture(GrayView gray);
// Two gray images of one height side by side (left | right), in colour.
RgbImage side_by_side(GrayView left, GrayView right);

// The colour of t in [0, 1] on OpenCV's perceptual TURBO map: dark blue (0: far, small
// disparities) through green and yellow to dark red (1: near).
cv::Scalar colour_of(double t);

// Text in OpenCV's Hershey font on a dark box, so that it reads on any image. `top_left` is the
// box's corner; the box is moved inside the picture when it would leave it.
void draw_label(cv::Mat& picture, cv::Point top_left, const std::string& text, cv::Scalar colour);
// The height of a label's box, pixels.
int label_height();

// The disparity (x16, vision::kInvalidDisparity: black) on the TURBO map, above a legend of
// kLegendHeight rows: its title with the unit, the colour bar from 0 to max_disparity and ticks
// labelled in pixels.
constexpr int kLegendHeight = 40;
RgbImage disparity_picture(ImageView<const std::int16_t> disparity, int max_disparity);

}  // namespace epipole::tools
