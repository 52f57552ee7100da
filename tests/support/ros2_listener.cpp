// epipole-ros2-listener: a ROS 2 subscriber of the firmware's topics for the tests, a DDS
// participant of its own process (CycloneDDS, configured as every CycloneDDS program is, by
// CYCLONEDDS_URI: the tests pass a loopback-only file). It says "ready" on standard error once
// each of its readers has matched a writer (the firmware's, made before), takes what comes until
// nothing came for half a second (or SECONDS passed), then prints one JSON object with every
// message decoded as tests/clients/mcap-read.mjs prints a recording's (so that one test checks
// both). Exit status 0 when it took left images, 3 when none came, 4 when not every topic
// matched.
//
//   epipole-ros2-listener DOMAIN NAMESPACE SECONDS [GRID]
#include <dds/dds.h>

#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <iostream>
#include <nlohmann/json.hpp>
#include <string>
#include <thread>
#include <vector>

#include "listening.hpp"
#include "ros2_types.h"

namespace {

using nlohmann::json;

int grid = 6;

std::uint32_t fnv1a(const std::uint8_t* data, std::uint32_t width_bytes, std::uint32_t height,
                    std::uint32_t step) {
  std::uint32_t h = 0x811c9dc5u;
  for (std::uint32_t y = 0; y < height; ++y) {
    for (std::uint32_t i = 0; i < width_bytes; ++i) {
      h ^= data[y * step + i];
      h *= 0x01000193u;
    }
  }
  return h;
}

json stamp_of(const std_msgs_msg_dds__Header_& h) {
  return {h.stamp.sec, h.stamp.nanosec};
}

std::string log_time(const std_msgs_msg_dds__Header_& h) {
  return std::to_string(static_cast<std::int64_t>(h.stamp.sec) * 1'000'000'000 + h.stamp.nanosec);
}

json image_summary(const sensor_msgs_msg_dds__Image_& m) {
  const std::string encoding = m.encoding;
  const std::uint32_t bpp = encoding == "mono8" ? 1 : encoding == "16UC1" ? 2 : 4;
  json samples = json::array();
  for (int j = 0; j < grid; ++j) {
    for (int i = 0; i < grid; ++i) {
      const auto x = static_cast<std::uint32_t>((i + 0.5) * m.width / grid);
      const auto y = static_cast<std::uint32_t>((j + 0.5) * m.height / grid);
      const std::uint8_t* at = m.data._buffer + y * m.step + x * bpp;
      json value;
      if (bpp == 1) {
        value = *at;
      } else if (bpp == 2) {
        std::uint16_t v;
        std::memcpy(&v, at, 2);
        value = v;
      } else {
        float v;
        std::memcpy(&v, at, 4);
        value = v;
      }
      samples.push_back({x, y, value});
    }
  }
  return {{"frame_id", m.header.frame_id},
          {"width", m.width},
          {"height", m.height},
          {"encoding", encoding},
          {"step", m.step},
          {"is_bigendian", m.is_bigendian},
          {"hash", fnv1a(m.data._buffer, m.width * bpp, m.height, m.step)},
          {"samples", samples},
          {"data_length", m.data._length}};
}

json cloud_summary(const sensor_msgs_msg_dds__PointCloud2_& m) {
  json fields = json::array();
  for (std::uint32_t i = 0; i < m.fields._length; ++i) {
    const auto& f = m.fields._buffer[i];
    fields.push_back({f.name, f.offset, f.datatype, f.count});
  }
  json points = json::array();
  for (std::uint32_t i = 0; i < m.width * m.height; ++i) {
    float p[4];
    std::memcpy(p, m.data._buffer + i * m.point_step, sizeof p);
    json point = json::array();
    for (const float v : p) point.push_back(std::isfinite(v) ? json(v) : json(nullptr));
    points.push_back(point);
  }
  return {{"frame_id", m.header.frame_id},
          {"width", m.width},
          {"height", m.height},
          {"fields", fields},
          {"point_step", m.point_step},
          {"row_step", m.row_step},
          {"is_dense", m.is_dense},
          {"points", points}};
}

struct Topic {
  std::string name;
  const dds_topic_descriptor_t* type;
  const char* type_name;
  bool latched = false;
  dds_entity_t reader = 0;
};

}  // namespace

int main(int argc, char** argv) {
  if (argc < 4) {
    std::fprintf(stderr, "usage: epipole-ros2-listener DOMAIN NAMESPACE SECONDS [GRID]\n");
    return 2;
  }
  const auto domain = static_cast<dds_domainid_t>(std::stoi(argv[1]));
  const std::string ns = argv[2];
  const int seconds = std::stoi(argv[3]);
  if (argc > 4) grid = std::stoi(argv[4]);
  const auto deadline = epipole::test::ListenClock::now() + std::chrono::seconds(seconds);
  const dds_entity_t participant = dds_create_participant(domain, nullptr, nullptr);
  if (participant < 0) {
    std::fprintf(stderr, "listener: %s\n", dds_strretcode(participant));
    return 1;
  }
  std::vector<Topic> topics = {
      {ns + "/left/image_rect", &sensor_msgs_msg_dds__Image__desc, "sensor_msgs/msg/Image"},
      {ns + "/right/image_rect", &sensor_msgs_msg_dds__Image__desc, "sensor_msgs/msg/Image"},
      {ns + "/left/camera_info", &sensor_msgs_msg_dds__CameraInfo__desc,
       "sensor_msgs/msg/CameraInfo"},
      {ns + "/right/camera_info", &sensor_msgs_msg_dds__CameraInfo__desc,
       "sensor_msgs/msg/CameraInfo"},
      {ns + "/disparity", &stereo_msgs_msg_dds__DisparityImage__desc,
       "stereo_msgs/msg/DisparityImage"},
      {ns + "/depth", &sensor_msgs_msg_dds__Image__desc, "sensor_msgs/msg/Image"},
      {ns + "/points", &sensor_msgs_msg_dds__PointCloud2__desc, "sensor_msgs/msg/PointCloud2"},
      {ns + "/features", &sensor_msgs_msg_dds__PointCloud2__desc, "sensor_msgs/msg/PointCloud2"},
      {"/diagnostics", &diagnostic_msgs_msg_dds__DiagnosticArray__desc,
       "diagnostic_msgs/msg/DiagnosticArray"},
      {"/tf", &tf2_msgs_msg_dds__TFMessage__desc, "tf2_msgs/msg/TFMessage"},
      {"/tf_static", &tf2_msgs_msg_dds__TFMessage__desc, "tf2_msgs/msg/TFMessage", true},
  };
  for (Topic& t : topics) {
    const dds_entity_t topic =
        dds_create_topic(participant, t.type, ("rt" + t.name).c_str(), nullptr, nullptr);
    dds_qos_t* qos = dds_create_qos();
    dds_qset_reliability(qos, DDS_RELIABILITY_RELIABLE, DDS_SECS(1));
    dds_qset_history(qos, DDS_HISTORY_KEEP_LAST, t.latched ? 1 : 200);
    dds_qset_durability(qos, t.latched ? DDS_DURABILITY_TRANSIENT_LOCAL : DDS_DURABILITY_VOLATILE);
    t.reader = dds_create_reader(participant, topic, qos, nullptr);
    dds_delete_qos(qos);
    if (t.reader < 0) {
      std::fprintf(stderr, "listener: reader of %s: %s\n", t.name.c_str(),
                   dds_strretcode(t.reader));
      return 1;
    }
  }
  std::vector<std::string> names;
  for (const Topic& t : topics) names.push_back(t.name);
  if (!epipole::test::wait_for_writers(names, deadline, [&](std::size_t i) {
        dds_subscription_matched_status_t matched{};
        return dds_get_subscription_matched_status(topics[i].reader, &matched) == DDS_RETCODE_OK &&
               matched.current_count > 0;
      })) {
    return 4;
  }

  json messages = json::array();
  int left_images = 0;
  epipole::test::take_until_quiet(
      deadline,
      [&] {
        bool any = false;
        for (Topic& t : topics) {
          void* samples[1] = {nullptr};
          dds_sample_info_t info[1];
          while (dds_take(t.reader, samples, info, 1, 1) > 0) {
            any = true;
            if (!info[0].valid_data) {
              dds_return_loan(t.reader, samples, 1);
              continue;
            }
            json m = {{"topic", t.name}, {"type", t.type_name}};
            if (t.type == &sensor_msgs_msg_dds__Image__desc) {
              const auto& s = *static_cast<sensor_msgs_msg_dds__Image_*>(samples[0]);
              m.update(image_summary(s));
              m["stamp"] = stamp_of(s.header);
              m["log_time"] = log_time(s.header);
              if (t.name == ns + "/left/image_rect") ++left_images;
            } else if (t.type == &sensor_msgs_msg_dds__CameraInfo__desc) {
              const auto& s = *static_cast<sensor_msgs_msg_dds__CameraInfo_*>(samples[0]);
              m.update({{"frame_id", s.header.frame_id},
                        {"width", s.width},
                        {"height", s.height},
                        {"distortion_model", s.distortion_model},
                        {"d", std::vector<double>(s.d._buffer, s.d._buffer + s.d._length)},
                        {"k", std::vector<double>(s.k, s.k + 9)},
                        {"r", std::vector<double>(s.r, s.r + 9)},
                        {"p", std::vector<double>(s.p, s.p + 12)},
                        {"stamp", stamp_of(s.header)},
                        {"log_time", log_time(s.header)}});
            } else if (t.type == &stereo_msgs_msg_dds__DisparityImage__desc) {
              const auto& s = *static_cast<stereo_msgs_msg_dds__DisparityImage_*>(samples[0]);
              m.update({{"frame_id", s.header.frame_id},
                        {"f", s.f},
                        {"t", s.t},
                        {"min_disparity", s.min_disparity},
                        {"max_disparity", s.max_disparity},
                        {"delta_d", s.delta_d},
                        {"image", image_summary(s.image)},
                        {"stamp", stamp_of(s.header)},
                        {"log_time", log_time(s.header)}});
            } else if (t.type == &sensor_msgs_msg_dds__PointCloud2__desc) {
              const auto& s = *static_cast<sensor_msgs_msg_dds__PointCloud2_*>(samples[0]);
              m.update(cloud_summary(s));
              m["stamp"] = stamp_of(s.header);
              m["log_time"] = log_time(s.header);
            } else if (t.type == &diagnostic_msgs_msg_dds__DiagnosticArray__desc) {
              const auto& s = *static_cast<diagnostic_msgs_msg_dds__DiagnosticArray_*>(samples[0]);
              json status = json::array();
              for (std::uint32_t i = 0; i < s.status._length; ++i) {
                const auto& st = s.status._buffer[i];
                json values = json::object();
                for (std::uint32_t k = 0; k < st.values._length; ++k) {
                  values[st.values._buffer[k].key] = st.values._buffer[k].value;
                }
                status.push_back({{"level", st.level},
                                  {"name", st.name},
                                  {"message", st.message},
                                  {"hardware_id", st.hardware_id},
                                  {"values", values}});
              }
              m["status"] = status;
              m["log_time"] = log_time(s.header);
            } else {
              const auto& s = *static_cast<tf2_msgs_msg_dds__TFMessage_*>(samples[0]);
              json transforms = json::array();
              for (std::uint32_t i = 0; i < s.transforms._length; ++i) {
                const auto& tr = s.transforms._buffer[i];
                const auto& v = tr.transform.translation;
                const auto& q = tr.transform.rotation;
                transforms.push_back(
                    {{"parent", tr.header.frame_id},
                     {"child", tr.child_frame_id},
                     {"translation", {{"x", v.x}, {"y", v.y}, {"z", v.z}}},
                     {"rotation", {{"x", q.x}, {"y", q.y}, {"z", q.z}, {"w", q.w}}}});
              }
              m["transforms"] = transforms;
              if (s.transforms._length > 0) {
                m["stamp"] = stamp_of(s.transforms._buffer[0].header);
                m["log_time"] = log_time(s.transforms._buffer[0].header);
              }
            }
            messages.push_back(m);
            dds_return_loan(t.reader, samples, 1);
          }
        }
        return any;
      },
      [&] { return left_images > 0; });
  dds_delete(participant);
  std::cout << json{{"messages", messages}}.dump() << "\n";
  return left_images > 0 ? 0 : 3;
}
