#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>

#include "epipole/firmware/protocol/cobs.hpp"
#include "epipole/firmware/protocol/messages.hpp"

namespace epipole::protocol {

// A frame on the wire: COBS(version u8, type u8, sequence u16, body, crc32 u32) then 0x00.
// The CRC covers version .. body.
inline constexpr std::size_t kHeaderSize = 4;
inline constexpr std::size_t kCrcSize = 4;
inline constexpr std::size_t kMaxBodySize = 800;
inline constexpr std::size_t kMaxPayloadSize = kHeaderSize + kMaxBodySize + kCrcSize;
inline constexpr std::size_t kMaxFrameSize = cobs_max_encoded_size(kMaxPayloadSize) + 1;

// Encodes one message into a complete frame in `out` (at least kMaxFrameSize bytes is always
// enough); returns the frame's size. Throws Error for a message whose counts exceed the limits.
std::size_t encode_frame(const Message& message, std::uint16_t sequence,
                         std::span<std::uint8_t> out);

struct DecodedMessage {
  std::uint16_t sequence = 0;
  Message message;
  bool replay = false;  // a sequence number already delivered (only when replays are delivered)
};

// What the decoder has seen: every byte it was fed lands in exactly one bucket.
struct DecoderStats {
  std::uint64_t frames = 0;    // valid frames delivered
  std::uint64_t bad_cobs = 0;  // not a COBS encoding
  std::uint64_t too_long = 0;  // longer than any valid frame
  std::uint64_t bad_crc = 0;
  std::uint64_t bad_version = 0;
  std::uint64_t unknown_type = 0;
  std::uint64_t bad_body = 0;  // wrong length or counts for its type
  std::uint64_t replays = 0;   // a sequence number already delivered: dropped (or flagged)
  std::uint64_t lost = 0;      // sequence numbers skipped (frames lost on the way)
  std::uint64_t resyncs = 0;   // the sender restarted its sequence (at 0, or far behind)
  std::uint64_t empty = 0;     // 0x00 with nothing before it (line idle, resync)
};

// Turns an untrusted byte stream into messages. Fixed memory, never throws, never allocates:
// garbage, truncated frames and bit errors are counted and skipped, and decoding resumes at
// the next 0x00.
//
// Sequence numbers (docs/protocol.md): a sender starts at 0 and counts up, wrapping. A frame
// numbered 0 that neither follows 65535 nor repeats the last frame is a sender that restarted
// (a resync, delivered); one up to 63 behind the last (or the last itself) is a replay when that
// number was delivered (dropped, or with `deliver_replays` delivered flagged, so that a command
// sent again is answered without being applied again), and a late frame, delivered, when it
// was not; further behind, the sender restarted too.
class FrameDecoder {
 public:
  explicit FrameDecoder(bool deliver_replays = false) : deliver_replays_(deliver_replays) {}
  // Feeds one byte; returns a message when the byte completes a valid frame.
  std::optional<DecodedMessage> push(std::uint8_t byte);
  // Forgets the frame in progress and the last sequence number: the link was closed and
  // opened again, so whatever comes next starts afresh.
  void reset();
  const DecoderStats& stats() const { return stats_; }

 private:
  // A sequence number up to this far behind the last one is a replay; further behind, the
  // sender restarted.
  static constexpr int kReplayWindow = 64;
  bool deliver_replays_;

  std::optional<DecodedMessage> finish_frame();

  std::array<std::uint8_t, cobs_max_encoded_size(kMaxPayloadSize)> encoded_{};
  std::array<std::uint8_t, kMaxPayloadSize> payload_{};
  std::size_t size_ = 0;
  bool overflowed_ = false;
  bool have_sequence_ = false;
  std::uint16_t last_sequence_ = 0;
  std::uint64_t delivered_ = 0;  // bit k: last_sequence_ - k was delivered
  DecoderStats stats_;
};

// Decodes the body of a message of a given type; nullopt when the body is not valid for it.
std::optional<Message> decode_body(MessageType type, std::span<const std::uint8_t> body);

}  // namespace epipole::protocol
