// libFuzzer target: arbitrary bytes into the MAVLink stream decoder (what `epipole link` and
// `epipole sim` read a MAVLink board's link with). Every frame it delivers must decode as one of
// its two messages, and no byte may be counted twice (in a frame and as skipped).
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <vector>

#include "epipole/firmware/protocol/mavlink.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace epipole::mavlink;
  StreamDecoder decoder;
  std::size_t frame_bytes = 0;
  for (std::size_t i = 0; i < size; ++i) {
    const auto frame = decoder.push(data[i]);
    if (!frame) continue;
    frame_bytes += kHeaderSize + frame->length + kChecksumSize;
    const bool heartbeat = decode_heartbeat(*frame).has_value();
    const bool obstacles = decode_obstacle_distance(*frame).has_value();
    if (heartbeat == obstacles) std::abort();  // exactly one of the two messages
  }
  const StreamStats& s = decoder.stats();
  if (frame_bytes + s.skipped_bytes > size) {
    std::abort();
  }
  return 0;
}
