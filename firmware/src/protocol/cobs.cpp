#include "epipole/firmware/protocol/cobs.hpp"

namespace epipole::protocol {

std::optional<std::size_t> cobs_encode(std::span<const std::uint8_t> in,
                                       std::span<std::uint8_t> out) {
  if (out.size() < cobs_max_encoded_size(in.size())) return std::nullopt;
  std::size_t code_at = 0;  // where the current block's code byte goes
  std::size_t size = 1;
  std::uint8_t code = 1;
  for (const std::uint8_t byte : in) {
    if (byte != 0) {
      out[size++] = byte;
      ++code;
    }
    if (byte == 0 || code == 0xFF) {
      out[code_at] = code;
      code_at = size++;
      code = 1;
    }
  }
  out[code_at] = code;
  return size;
}

std::optional<std::size_t> cobs_decode(std::span<const std::uint8_t> in,
                                       std::span<std::uint8_t> out) {
  std::size_t read = 0;
  std::size_t size = 0;
  while (read < in.size()) {
    const std::uint8_t code = in[read++];
    if (code == 0 || read + code - 1 > in.size()) return std::nullopt;
    for (int i = 1; i < code; ++i) {
      const std::uint8_t byte = in[read++];
      if (byte == 0 || size == out.size()) return std::nullopt;
      out[size++] = byte;
    }
    // A block shorter than 254 data bytes stands for a zero, unless it ends the frame.
    if (code != 0xFF && read < in.size()) {
      if (size == out.size()) return std::nullopt;
      out[size++] = 0;
    }
  }
  return size;
}

}  // namespace epipole::protocol
