// libFuzzer target: arbitrary bytes as a calibration in each format the project reads. The first
// byte picks the format: Epipole's own YAML (anything else), OpenCV's stereo files as the host
// tool reads them with cv::FileStorage (intrinsics and extrinsics, YAML, XML or JSON: 'o') or
// ROS camera_info files (left and right: 'r'), the rest split in two at the first 0x00. An
// accepted calibration is valid, and Epipole's own file of it reads back as the same
// calibration text; a refused one is an Error.
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <span>
#include <string>

#include "epipole/calib/calibration.hpp"
#include "epipole/core/error.hpp"
#include "epipole/tools/opencv_calibration.hpp"
#include "fuzz_file.hpp"

namespace {

void check(const epipole::calib::StereoCalibration& calibration) {
  using namespace epipole::calib;
  validate(calibration);
  const std::string text = format_calibration(calibration);
  if (format_calibration(parse_calibration(text, "again.yaml")) != text) std::abort();
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace epipole;
  if (size == 0) return 0;
  const char format = static_cast<char>(data[0]);
  const std::span<const std::uint8_t> rest(data + 1, size - 1);
  std::size_t split = 0;
  while (split < rest.size() && rest[split] != 0) ++split;
  const std::span<const std::uint8_t> first = rest.first(split);
  const std::span<const std::uint8_t> second =
      split < rest.size() ? rest.subspan(split + 1) : std::span<const std::uint8_t>{};
  try {
    if (format == 'o') {
      check(tools::import_opencv_calibration(fuzz::write_file("intrinsics.yml", first),
                                             fuzz::write_file("extrinsics.yml", second)));
    } else if (format == 'r') {
      check(calib::import_ros_calibration(fuzz::write_file("left.yaml", first),
                                          fuzz::write_file("right.yaml", second)));
    } else {
      check(calib::parse_calibration(
          std::string(reinterpret_cast<const char*>(rest.data()), rest.size()), "fuzz.yaml"));
    }
  } catch (const Error&) {
    // Bad input is an Error: that is what the readers must do.
  }
  return 0;
}
