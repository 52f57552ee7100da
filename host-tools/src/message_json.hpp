#pragma once

// The serial link's messages as JSON, for people and scripts (epipole link, epipole sim): the
// native protocol's messages, or MAVLink's when the board speaks MAVLink.
#include <cstdint>
#include <nlohmann/json.hpp>
#include <optional>

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

  // Feeds one byte; returns the message it completes. After a message, next() until none.
  std::optional<nlohmann::json> push(std::uint8_t byte);
  // A further message complete in what was fed (MAVLink: frames held back by a false start).
  std::optional<nlohmann::json> next();
  // The stream has ended: what is still to be found in it, until none.
  std::optional<nlohmann::json> finish();
  // {"type": "decoder", "protocol": ..., every counter of the decoder, "errors": their faults}.
  nlohmann::json stats() const;

 private:
  Protocol protocol_;
  protocol::FrameDecoder native_;
  mavlink::StreamDecoder mavlink_;
};

}  // namespace epipole::tools
