#include "message_json.hpp"

#include <variant>

#include "epipole/firmware/protocol/fields.hpp"

namespace epipole::tools {

using namespace epipole::protocol;

namespace {

// A protocol field visitor that builds a JSON object.
struct JsonFields {
  nlohmann::json* object;
  template <class T>
  void operator()(const char* name, const T& value) {
    if constexpr (std::is_enum_v<T>) {
      (*object)[name] = static_cast<int>(value);
    } else {
      (*object)[name] = value;
    }
  }
  template <class Items, class Each>
  void list(const char* name, std::uint8_t count, int, const Items& items, Each each) {
    nlohmann::json array = nlohmann::json::array();
    for (int i = 0; i < count; ++i) {
      nlohmann::json item = nlohmann::json::object();
      JsonFields item_fields{&item};
      each(item_fields, items[i]);
      // A one-field item (a sector's distance) is just its value.
      array.push_back(item.size() == 1 ? item.begin().value() : item);
    }
    (*object)[name] = std::move(array);
  }
};

}  // namespace

nlohmann::json to_json(const DecodedMessage& decoded) {
  nlohmann::json out = {{"seq", decoded.sequence}, {"type", name_of(type_of(decoded.message))}};
  std::visit(
      [&out](const auto& m) {
        JsonFields json_fields{&out};
        fields(json_fields, m);
      },
      decoded.message);
  return out;
}

nlohmann::json stats_json(const DecoderStats& s) {
  return {{"type", "decoder"},
          {"frames", s.frames},
          {"bad_cobs", s.bad_cobs},
          {"too_long", s.too_long},
          {"bad_crc", s.bad_crc},
          {"bad_version", s.bad_version},
          {"unknown_type", s.unknown_type},
          {"bad_body", s.bad_body},
          {"replays", s.replays},
          {"lost", s.lost},
          {"resyncs", s.resyncs}};
}

}  // namespace epipole::tools
