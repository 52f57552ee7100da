// libFuzzer target: arbitrary bytes as a calibration in the formats the firmware's library
// reads. The first byte picks the format: Epipole's own YAML (anything but 'r') or ROS
// camera_info files (left and right: 'r', the rest split in two at the first 0x00). An accepted
// calibration is valid, and Epipole's own file of it reads back as the same calibration text; a
// refused one is an Error. OpenCV's files have their own target, opencv_calibration_fuzz.
#include <cstddef>
#include <cstdint>
#include <span>
#include <string>

#include "calibration_round_trip.hpp"
#include "epipole/calib/calibration.hpp"
#include "epipole/core/error.hpp"
#include "fuzz_file.hpp"

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
    if (format == 'r') {
      fuzz::check_round_trip(calib::import_ros_calibration(fuzz::write_file("left.yaml", first),
                                                           fuzz::write_file("right.yaml", second)));
    } else {
      fuzz::check_round_trip(calib::parse_calibration(
          std::string(reinterpret_cast<const char*>(rest.data()), rest.size()), "fuzz.yaml"));
    }
  } catch (const Error&) {
    // Bad input is an Error: that is what the readers must do.
  }
  return 0;
}
