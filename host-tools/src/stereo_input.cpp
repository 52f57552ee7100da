#include "stereo_input.hpp"

#include "epipole/core/error.hpp"
#include "epipole/core/image_io.hpp"

namespace epipole::tools {

StereoInput load_stereo_input(const std::string& left, const std::string& right,
                              const std::string& calib, SimdPath path) {
  StereoInput in;
  in.left_image = load_gray(left);
  in.right_image = load_gray(right);
  require(same_size(in.left_image.view(), in.right_image.view()), "the left image ", left, " is ",
          in.left_image.width(), "x", in.left_image.height(), " but the right image ", right,
          " is ", in.right_image.width(), "x", in.right_image.height(),
          ": a stereo pair must have one size");
  in.left = in.left_image.view();
  in.right = in.right_image.view();
  if (!calib.empty()) {
    in.calibration = calib::load_calibration(calib);
    require(in.calibration->width == in.left_image.width() &&
                in.calibration->height == in.left_image.height(),
            "the images are ", in.left_image.width(), "x", in.left_image.height(), " but ", calib,
            " is a calibration for ", in.calibration->width, "x", in.calibration->height);
    in.rectifiers.emplace(firmware::make_stereo_rectifiers(*in.calibration, path));
    in.left = in.rectifiers->left.rectify(in.left);
    in.right = in.rectifiers->right.rectify(in.right);
  }
  return in;
}

}  // namespace epipole::tools
