#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>

namespace epipole::protocol {

// Consistent Overhead Byte Stuffing: the encoded bytes contain no 0x00, so a 0x00 can end
// every frame and a receiver that joins mid-stream resynchronises at the next one.

// The largest encoding of n bytes.
constexpr std::size_t cobs_max_encoded_size(std::size_t n) {
  return n + n / 254 + 1;
}

// Encodes `in` into `out` (no delimiter); returns the encoded size, or nullopt when `out` is
// too small.
std::optional<std::size_t> cobs_encode(std::span<const std::uint8_t> in,
                                       std::span<std::uint8_t> out);

// Decodes one frame's bytes (without the delimiter) into `out`; nullopt when the bytes are not
// a valid encoding (a 0x00 inside, a code running past the end) or `out` is too small.
std::optional<std::size_t> cobs_decode(std::span<const std::uint8_t> in,
                                       std::span<std::uint8_t> out);

}  // namespace epipole::protocol
