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

nlohmann::json native_stats(const DecoderStats& s) {
  return {{"type", "decoder"},
          {"protocol", "epipole"},
          {"frames", s.frames},
          {"bad_cobs", s.bad_cobs},
          {"too_long", s.too_long},
          {"bad_crc", s.bad_crc},
          {"bad_version", s.bad_version},
          {"unknown_type", s.unknown_type},
          {"bad_body", s.bad_body},
          {"replays", s.replays},
          {"lost", s.lost},
          {"resyncs", s.resyncs},
          {"errors", s.bad_cobs + s.too_long + s.bad_crc + s.bad_version + s.unknown_type +
                         s.bad_body + s.replays + s.lost}};
}

// errors: frames damaged, cut short or lost; messages of other kinds (a flight controller's own)
// and bytes between frames are not errors.
nlohmann::json mavlink_stats(const mavlink::StreamStats& s) {
  return {{"type", "decoder"},
          {"protocol", "mavlink"},
          {"frames", s.frames},
          {"bad_crc", s.bad_crc},
          {"unknown_message", s.unknown_message},
          {"bad_flags", s.bad_flags},
          {"truncated", s.truncated},
          {"skipped_bytes", s.skipped_bytes},
          {"lost", s.lost},
          {"restarts", s.restarts},
          {"errors", s.bad_crc + s.bad_flags + s.truncated + s.lost}};
}

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

namespace {

// A text from the wire as JSON can carry it: bytes outside printable ASCII (a flight
// controller's own STATUSTEXT may hold any) become '?'.
std::string printable(const char* text) {
  std::string out(text);
  for (char& c : out) {
    if (c < 0x20 || c > 0x7e) c = '?';
  }
  return out;
}

}  // namespace

nlohmann::json to_json(const mavlink::Frame& frame) {
  nlohmann::json out = {{"seq", frame.sequence},
                        {"type", "unknown"},
                        {"system_id", frame.system_id},
                        {"component_id", frame.component_id}};
  if (const auto h = mavlink::decode_heartbeat(frame)) {
    out["type"] = "heartbeat";
    out["mav_type"] = h->type;
    out["autopilot"] = h->autopilot;
    out["base_mode"] = h->base_mode;
    out["system_status"] = h->system_status;
    out["mavlink_version"] = h->mavlink_version;
  } else if (const auto m = mavlink::decode_obstacle_distance(frame)) {
    out["type"] = "obstacle_distance";
    out["time_usec"] = m->time_usec;
    out["sensor_type"] = m->sensor_type;
    out["frame"] = m->frame;
    out["increment_deg"] = m->increment_deg;
    out["angle_offset_deg"] = m->angle_offset_deg;
    out["min_distance_cm"] = m->min_distance_cm;
    out["max_distance_cm"] = m->max_distance_cm;
    // Sectors past the field of view are unused (UINT16_MAX), as are sectors of unknown depth;
    // max_distance_cm + 1 means nothing is there.
    out["distances_cm"] = m->distances_cm;
    nlohmann::json nearest = nullptr;
    for (const std::uint16_t d : m->distances_cm) {
      if (d >= m->min_distance_cm && d <= m->max_distance_cm &&
          (nearest.is_null() || d < nearest.get<int>())) {
        nearest = d;
      }
    }
    out["nearest_cm"] = nearest;
  } else if (const auto v = mavlink::decode_named_value_float(frame)) {
    out["type"] = "named_value_float";
    out["time_boot_ms"] = v->time_boot_ms;
    out["name"] = printable(v->name.data());
    out["value"] = v->value;
  } else if (const auto t = mavlink::decode_status_text(frame)) {
    out["type"] = "statustext";
    out["severity"] = t->severity;
    out["text"] = printable(t->text.data());
  } else if (const auto o = mavlink::decode_odometry(frame)) {
    // Floats as sent; NaN (an unknown covariance) becomes null.
    out["type"] = "odometry";
    out["time_usec"] = o->time_usec;
    out["frame_id"] = o->frame_id;
    out["child_frame_id"] = o->child_frame_id;
    out["x"] = o->x;
    out["y"] = o->y;
    out["z"] = o->z;
    out["q"] = o->q;  // w, x, y, z
    out["vx"] = o->vx;
    out["vy"] = o->vy;
    out["vz"] = o->vz;
    out["rollspeed"] = o->rollspeed;
    out["pitchspeed"] = o->pitchspeed;
    out["yawspeed"] = o->yawspeed;
    out["pose_covariance"] = o->pose_covariance;
    out["velocity_covariance"] = o->velocity_covariance;
    out["reset_counter"] = o->reset_counter;
    out["estimator_type"] = o->estimator_type;
    out["quality"] = o->quality;
  } else if (const auto s = mavlink::decode_timesync(frame)) {
    out["type"] = "timesync";
    out["tc1"] = s->tc1;
    out["ts1"] = s->ts1;
    out["target_system"] = s->target_system;
    out["target_component"] = s->target_component;
  }
  return out;
}

std::optional<nlohmann::json> JsonStreamDecoder::push(std::uint8_t byte) {
  if (protocol_ == Protocol::mavlink) {
    if (const auto frame = mavlink_.push(byte)) return to_json(*frame);
  } else if (const auto decoded = native_.push(byte)) {
    return to_json(*decoded);
  }
  return std::nullopt;
}

std::optional<nlohmann::json> JsonStreamDecoder::next() {
  if (protocol_ == Protocol::mavlink) {
    if (const auto frame = mavlink_.next()) return to_json(*frame);
  }
  return std::nullopt;  // the native decoder delivers every frame when its 0x00 arrives
}

std::optional<nlohmann::json> JsonStreamDecoder::finish_one() {
  if (protocol_ == Protocol::mavlink) {
    if (const auto frame = mavlink_.finish()) return to_json(*frame);
  }
  return std::nullopt;
}

nlohmann::json JsonStreamDecoder::stats() const {
  return protocol_ == Protocol::mavlink ? mavlink_stats(mavlink_.stats())
                                        : native_stats(native_.stats());
}

}  // namespace epipole::tools
