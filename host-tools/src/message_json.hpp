#pragma once

// The serial protocol's messages as JSON, for people and scripts (epipole link, epipole sim).
#include <nlohmann/json.hpp>

#include "epipole/firmware/protocol/codec.hpp"

namespace epipole::tools {

// {"seq": N, "type": "health", <the message's fields>}.
nlohmann::json to_json(const protocol::DecodedMessage& decoded);
// {"type": "decoder", <every counter of the decoder>}.
nlohmann::json stats_json(const protocol::DecoderStats& stats);

}  // namespace epipole::tools
