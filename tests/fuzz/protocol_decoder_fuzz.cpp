// libFuzzer target: arbitrary bytes into the serial protocol's FrameDecoder. Every message it
// delivers must encode again to a frame that decodes to the same message.
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <vector>

#include "epipole/firmware/protocol/codec.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace epipole::protocol;
  FrameDecoder decoder;
  std::vector<std::uint8_t> frame(kMaxFrameSize);
  for (std::size_t i = 0; i < size; ++i) {
    const auto decoded = decoder.push(data[i]);
    if (!decoded) continue;
    const std::size_t n = encode_frame(decoded->message, decoded->sequence, frame);
    FrameDecoder again;
    std::optional<DecodedMessage> round_trip;
    for (std::size_t k = 0; k < n; ++k) {
      if (auto m = again.push(frame[k])) round_trip = std::move(m);
    }
    if (!round_trip || round_trip->message != decoded->message ||
        round_trip->sequence != decoded->sequence) {
      std::abort();
    }
  }
  const DecoderStats& s = decoder.stats();
  if (s.frames > size) std::abort();
  return 0;
}
