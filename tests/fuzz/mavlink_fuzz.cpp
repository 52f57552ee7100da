// libFuzzer target: arbitrary bytes into the MAVLink stream decoder (what `epipole link` and
// `epipole sim` read a MAVLink board's link with, and the firmware reads an autopilot's TIMESYNC
// requests with). Every frame it delivers must decode as one of its six messages, and every byte
// must be in exactly one place: a delivered frame, the skipped bytes, or the buffer (empty once the
// stream has finished).
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <vector>

#include "epipole/firmware/protocol/mavlink.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace epipole::mavlink;
  StreamDecoder decoder;
  std::size_t frame_bytes = 0;
  const auto take = [&](const std::optional<Frame>& frame) {
    frame_bytes += frame->wire_size;
    if (!decode_heartbeat(*frame) && !decode_obstacle_distance(*frame) &&
        !decode_named_value_float(*frame) && !decode_status_text(*frame) &&
        !decode_odometry(*frame) && !decode_timesync(*frame)) {
      std::abort();
    }
  };
  for (std::size_t i = 0; i < size; ++i) {
    for (auto frame = decoder.push(data[i]); frame; frame = decoder.next()) take(frame);
    // Every byte so far is in a delivered frame, skipped, or still buffered: exactly one.
    if (frame_bytes + decoder.stats().skipped_bytes + decoder.buffered() != i + 1) std::abort();
  }
  for (auto frame = decoder.finish(); frame; frame = decoder.finish()) take(frame);
  if (decoder.buffered() != 0 || frame_bytes + decoder.stats().skipped_bytes != size) {
    std::abort();
  }
  return 0;
}
