// A recording as a scene: the raw left and right images of an MCAP recording (the firmware's
// recording output, docs/outputs.md, or any recording of sensor_msgs/Image topics named
// .../left/image_raw and .../right/image_raw), paired by their stamps.
#include <algorithm>
#include <map>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "epipole/core/cdr_reader.hpp"
#include "epipole/core/error.hpp"
#include "epipole/core/mcap_reader.hpp"
#include "sim/sim_files.hpp"
#include "sim/sim_scene.hpp"

namespace epipole::hal {

namespace {

constexpr std::string_view kImageType = "sensor_msgs/msg/Image";

bool ends_with(std::string_view s, std::string_view end) {
  return s.size() >= end.size() && s.substr(s.size() - end.size()) == end;
}

struct Stamped {
  std::int64_t stamp_ns = 0;
  GrayImage image;
};

// A sensor_msgs/Image in gray: mono8 (8UC1) as it is, rgb8 and bgr8 as their luma (BT.601).
Stamped decode_image(std::span<const std::uint8_t> bytes, const std::string& what) {
  cdr::CdrReader r(bytes, what);
  Stamped out;
  const std::int32_t sec = r.i32();
  const std::uint32_t nanosec = r.u32();
  out.stamp_ns = std::int64_t{sec} * 1'000'000'000 + nanosec;
  r.string();  // frame_id
  const std::uint32_t height = r.u32();
  const std::uint32_t width = r.u32();
  const std::string encoding(r.string());
  r.u8();  // is_bigendian: bytes have none
  const std::uint32_t step = r.u32();
  const std::span<const std::uint8_t> data = r.byte_sequence();
  const bool mono = encoding == "mono8" || encoding == "8UC1";
  const bool rgb = encoding == "rgb8";
  require(mono || rgb || encoding == "bgr8", what, ": encoding '", encoding,
          "' (mono8, rgb8 or bgr8 replay)");
  const std::uint32_t channels = mono ? 1 : 3;
  require(width >= 1 && height >= 1 && width <= 16384 && height <= 16384, what, ": ", width, "x",
          height, " is not an image size");
  require(step >= width * channels && std::uint64_t{step} * height <= data.size(), what, ": ",
          data.size(), " bytes cannot hold ", height, " rows of ", step, " bytes (", width, "x",
          height, " ", encoding, ")");
  out.image = GrayImage(static_cast<int>(width), static_cast<int>(height));
  for (std::uint32_t y = 0; y < height; ++y) {
    const std::uint8_t* in = data.data() + std::size_t{y} * step;
    std::uint8_t* row = out.image.view().row(static_cast<int>(y));
    if (mono) {
      std::copy_n(in, width, row);
      continue;
    }
    for (std::uint32_t x = 0; x < width; ++x) {
      const std::uint8_t* p = in + 3 * x;
      const unsigned red = rgb ? p[0] : p[2], blue = rgb ? p[2] : p[0];
      row[x] = static_cast<std::uint8_t>((77 * red + 150 * p[1] + 29 * blue + 128) >> 8);
    }
  }
  return out;
}

// The recording's left and right image topics.
struct RawTopics {
  std::map<std::uint16_t, std::string> schemas;  // by id: its name
  std::optional<std::uint16_t> left, right;
  std::string left_topic, right_topic;
};

void note_channel(RawTopics& t, const std::filesystem::path& file, std::uint16_t id,
                  const mcap::Channel& c) {
  const auto schema = t.schemas.find(c.schema_id);
  if (schema == t.schemas.end() || schema->second != kImageType || c.message_encoding != "cdr") {
    return;
  }
  for (auto [side, channel, topic] : {std::tuple{"left/image_raw", &t.left, &t.left_topic},
                                      std::tuple{"right/image_raw", &t.right, &t.right_topic}}) {
    if (!ends_with(c.topic, side)) continue;
    require(!*channel || *channel == id, file.string(), ": two topics of ", side, " images (",
            *topic, ", ", c.topic, "): which is replayed is not clear");
    *channel = id;
    *topic = c.topic;
  }
}

}  // namespace

StereoImages load_recording(const std::filesystem::path& file, const VideoOptions& options) {
  RawTopics topics;
  std::vector<Stamped> left, right;
  int width = 0, height = 0;  // of the recording's images: all one size, as one rig's
  const auto fitted = [&](Stamped s, const std::string& what) {
    if (width == 0) {
      width = s.image.width();
      height = s.image.height();
    }
    require(s.image.width() == width && s.image.height() == height, what, ": ", s.image.width(),
            "x", s.image.height(), " but the recording's images before were ", width, "x", height);
    if (options.fit_width > 0 && options.fit_height > 0) {
      s.image = letterbox(s.image.view(), options.fit_width, options.fit_height);
    }
    return s;
  };
  mcap::Visitor visit;
  visit.schema = [&](std::uint16_t id, const mcap::Schema& s) { topics.schemas[id] = s.name; };
  visit.channel = [&](std::uint16_t id, const mcap::Channel& c) {
    note_channel(topics, file, id, c);
  };
  visit.message = [&](const mcap::Message& m) {
    const bool is_left = m.channel == topics.left;
    if (!is_left && m.channel != topics.right) return;
    std::vector<Stamped>& images = is_left ? left : right;
    const std::string& topic = is_left ? topics.left_topic : topics.right_topic;
    require(images.size() < static_cast<std::size_t>(options.max_frames), file.string(),
            ": more than ", options.max_frames, " images on ", topic,
            " (max_frames: a scene is held in memory)");
    const std::string what = cat(file.string(), ": ", topic, " message ", m.sequence);
    images.push_back(fitted(decode_image(m.data, what), what));
  };
  mcap::scan_file(file, visit);
  require(topics.left && topics.right, file.string(),
          ": no sensor_msgs/Image topics .../left/image_raw and .../right/image_raw (the raw "
          "images a recording of the firmware holds)");
  // Paired by stamp (both are stamped with their pair's trigger), in the left images' order.
  std::map<std::int64_t, std::size_t> right_by_stamp;
  for (std::size_t i = 0; i < right.size(); ++i) right_by_stamp.emplace(right[i].stamp_ns, i);
  StereoImages pairs;
  for (Stamped& l : left) {
    const auto r = right_by_stamp.find(l.stamp_ns);
    if (r == right_by_stamp.end()) continue;
    pairs.left.push_back(std::move(l.image));
    pairs.right.push_back(std::move(right[r->second].image));
    right_by_stamp.erase(r);
  }
  require(!pairs.left.empty(), file.string(), ": no left and right images of one stamp (",
          left.size(), " left, ", right.size(), " right)");
  return pairs;
}

}  // namespace epipole::hal
