// libFuzzer target: arbitrary bytes as OpenCV's stereo calibration files, as the host tool reads
// them with cv::FileStorage (YAML, XML or JSON): intrinsics, then extrinsics after the first
// 0x00. An accepted calibration is valid and round-trips through Epipole's own file; a refused
// one is an Error. Each file is parsed in a child process first (OpenCV 4.6 hangs or crashes on
// some), so this target runs far fewer inputs a second than the others.
#include <cstddef>
#include <cstdint>
#include <span>

#include "calibration_round_trip.hpp"
#include "epipole/core/error.hpp"
#include "epipole/tools/opencv_calibration.hpp"
#include "fuzz_file.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace epipole;
  const std::span<const std::uint8_t> input(data, size);
  std::size_t split = 0;
  while (split < input.size() && input[split] != 0) ++split;
  const std::span<const std::uint8_t> second =
      split < input.size() ? input.subspan(split + 1) : std::span<const std::uint8_t>{};
  try {
    fuzz::check_round_trip(
        tools::import_opencv_calibration(fuzz::write_file("intrinsics.yml", input.first(split)),
                                         fuzz::write_file("extrinsics.yml", second)));
  } catch (const Error&) {
    // Bad input is an Error: that is what the readers must do.
  }
  return 0;
}
