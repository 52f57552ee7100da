#pragma once

// The serial link's messages as JSON, for people and scripts (epipole link, epipole sim): the
// native protocol's messages, or MAVLink's when the board speaks MAVLink.
#include <cstdint>
#include <nlohmann/json.hpp>
#include <optional>
#include <span>

#include "epipole/firmware/board_config.hpp"
#include "epipole/firmware/protocol/codec.hpp"
#include "epipole/firmware/protocol/mavlink.hpp"

namespace epipole::tools {

// {"seq": N, "type": "health", <the message's fields>}.
nlohmann::json to_json(const protocol::DecodedMessage& decoded);
// {"seq": N, "type": "heartbeat" or "obstacle_distance", "system_id", "component_id", <fields>}.
nlohmann::json to_json(const mavlink::Frame& frame);

// A link's byte stream decoded as one of the firmware's protocols.
class JsonStreamDecoder {
 public:
  using Protocol = firmware::BoardConfig::LinkProtocol;
  explicit JsonStreamDecoder(Protocol protocol) : protocol_(protocol) {}

  // Feeds bytes; calls take(message) for every message they complete (MAVLink: with the frames
  // a false start held back) while it returns true. False once it returned false.
  template <class Take>
  bool feed(std::span<const std::uint8_t> bytes, Take&& take) {
    for (const std::uint8_t b : bytes) {
      for (auto json = push(b); json; json = next()) {
        if (!take(*json)) return false;
      }
    }
    return true;
  }
  // The stream has ended: take() what is still to be found in it, while it returns true.
  template <class Take>
  void finish(Take&& take) {
    for (auto json = finish_one(); json; json = finish_one()) {
      if (!take(*json)) return;
    }
  }
  // {"type": "decoder", "protocol": ..., every counter of the decoder, "errors": their faults}.
  nlohmann::json stats() const;

 private:
  std::optional<nlohmann::json> push(std::uint8_t byte);
  std::optional<nlohmann::json> next();  // a further message complete in what was fed
  std::optional<nlohmann::json> finish_one();

  Protocol protocol_;
  protocol::FrameDecoder native_;
  mavlink::StreamDecoder mavlink_;
};

}  // namespace epipole::tools
