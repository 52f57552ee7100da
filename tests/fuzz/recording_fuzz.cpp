// libFuzzer target: arbitrary bytes as an MCAP recording replayed as a scene (the simulated
// board's `recording:`): the MCAP reader (records, chunks, zstd, CRCs) and the raw images'
// sensor_msgs/Image CDR. A file that reads gives pairs of one size, fitted to the board's; every
// other file is an Error.
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <span>

#include "epipole/core/error.hpp"
#include "fuzz_file.hpp"
#include "sim/sim_files.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace epipole;
  hal::VideoOptions options;
  options.max_frames = 8;
  options.fit_width = 32;
  options.fit_height = 24;
  try {
    const hal::StereoImages pairs =
        hal::load_recording(fuzz::write_file("recording.mcap", {data, size}), options);
    if (pairs.left.empty() || pairs.left.size() != pairs.right.size()) std::abort();
    for (std::size_t i = 0; i < pairs.left.size(); ++i) {
      if (pairs.left[i].width() != 32 || pairs.right[i].height() != 24) std::abort();
    }
  } catch (const Error&) {
    // Bad input is an Error: that is what the reader must do.
  }
  return 0;
}
