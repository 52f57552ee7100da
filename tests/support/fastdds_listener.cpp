// epipole-fastdds-listener: the tests' subscriber of another DDS vendor (eProsima Fast DDS, as
// ROS 2's default rmw uses it), in a process of its own, configured by the loopback-only
// profile the tests pass (FASTRTPS_DEFAULT_PROFILES_FILE). It knows the ROS 2 types by name only
// and decodes their CDR with Fast DDS's own library (Fast CDR), apart from CycloneDDS and from
// the firmware's code. Like epipole-ros2-listener: "ready" on standard error once every reader
// matched a writer, what comes until nothing came for half a second (or SECONDS passed), then
// one JSON object of the messages as tests/clients/mcap-read.mjs prints them. Topics: the left
// image, the left camera info, the depth, the points.
//
//   epipole-fastdds-listener DOMAIN NAMESPACE SECONDS [GRID]
#include <fastcdr/Cdr.h>
#include <fastcdr/FastBuffer.h>
#include <fastdds/dds/domain/DomainParticipant.hpp>
#include <fastdds/dds/domain/DomainParticipantFactory.hpp>
#include <fastdds/dds/subscriber/DataReader.hpp>
#include <fastdds/dds/subscriber/SampleInfo.hpp>
#include <fastdds/dds/subscriber/Subscriber.hpp>
#include <fastdds/dds/subscriber/qos/DataReaderQos.hpp>
#include <fastdds/dds/topic/TopicDataType.hpp>
#include <fastdds/dds/topic/TypeSupport.hpp>

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

namespace {

namespace fdds = eprosima::fastdds::dds;
using nlohmann::json;

int grid = 6;

// A sample as it came: the serialized bytes, encapsulation first.
struct RawSample {
  std::vector<std::uint8_t> bytes;
};

// A type known by its name alone: no type object, no type information (as ROS 2's own types
// are matched); the bytes are decoded by the reader's code below.
class RawType final : public fdds::TopicDataType {
 public:
  explicit RawType(const char* name) {
    setName(name);
    m_typeSize = 64 * 1024 * 1024;
    m_isGetKeyDefined = false;
    auto_fill_type_object(false);
    auto_fill_type_information(false);
  }
  bool serialize(void*, eprosima::fastrtps::rtps::SerializedPayload_t*) override { return false; }
  bool deserialize(eprosima::fastrtps::rtps::SerializedPayload_t* payload, void* data) override {
    auto* sample = static_cast<RawSample*>(data);
    sample->bytes.assign(payload->data, payload->data + payload->length);
    return true;
  }
  std::function<uint32_t()> getSerializedSizeProvider(void*) override {
    return [] { return 0u; };
  }
  void* createData() override { return new RawSample(); }
  void deleteData(void* data) override { delete static_cast<RawSample*>(data); }
  bool getKey(void*, eprosima::fastrtps::rtps::InstanceHandle_t*, bool) override { return false; }
};

struct Decoder {
  eprosima::fastcdr::FastBuffer buffer;
  eprosima::fastcdr::Cdr cdr;
  explicit Decoder(RawSample& s)
      : buffer(reinterpret_cast<char*>(s.bytes.data()), s.bytes.size()),
        cdr(buffer, eprosima::fastcdr::Cdr::DEFAULT_ENDIAN, eprosima::fastcdr::Cdr::DDS_CDR) {
    cdr.read_encapsulation();
  }
};

struct Header {
  std::int32_t sec = 0;
  std::uint32_t nanosec = 0;
  std::string frame_id;
};

Header header(eprosima::fastcdr::Cdr& cdr) {
  Header h;
  cdr >> h.sec >> h.nanosec >> h.frame_id;
  return h;
}

void stamp(json& m, const Header& h) {
  m["frame_id"] = h.frame_id;
  m["stamp"] = {h.sec, h.nanosec};
  m["log_time"] = std::to_string(static_cast<std::int64_t>(h.sec) * 1'000'000'000 + h.nanosec);
}

json image(eprosima::fastcdr::Cdr& cdr) {
  std::uint32_t height = 0, width = 0, step = 0;
  std::string encoding;
  std::uint8_t big = 0;
  std::vector<std::uint8_t> data;
  cdr >> height >> width >> encoding >> big >> step >> data;
  const std::uint32_t bpp = encoding == "mono8" ? 1 : encoding == "16UC1" ? 2 : 4;
  std::uint32_t hash = 0x811c9dc5u;
  for (std::uint32_t y = 0; y < height; ++y) {
    for (std::uint32_t i = 0; i < width * bpp; ++i) {
      hash ^= data.at(y * step + i);
      hash *= 0x01000193u;
    }
  }
  json samples = json::array();
  for (int j = 0; j < grid; ++j) {
    for (int i = 0; i < grid; ++i) {
      const auto x = static_cast<std::uint32_t>((i + 0.5) * width / grid);
      const auto y = static_cast<std::uint32_t>((j + 0.5) * height / grid);
      const std::uint8_t* at = data.data() + y * step + x * bpp;
      if (bpp == 1) {
        samples.push_back({x, y, *at});
      } else {
        std::uint16_t v;
        std::memcpy(&v, at, 2);
        samples.push_back({x, y, v});
      }
    }
  }
  return {{"width", width},      {"height", height}, {"encoding", encoding}, {"step", step},
          {"is_bigendian", big}, {"hash", hash},     {"samples", samples}};
}

json camera_info(eprosima::fastcdr::Cdr& cdr) {
  std::uint32_t height = 0, width = 0;
  std::string model;
  std::vector<double> d;
  std::array<double, 9> k{}, r{};
  std::array<double, 12> p{};
  cdr >> height >> width >> model >> d >> k >> r >> p;
  return {{"width", width}, {"height", height}, {"distortion_model", model},
          {"d", d},         {"k", k},           {"r", r},
          {"p", p}};
}

json diagnostics(eprosima::fastcdr::Cdr& cdr) {
  std::uint32_t count = 0;
  cdr >> count;
  json status = json::array();
  for (std::uint32_t i = 0; i < count; ++i) {
    std::uint8_t level = 0;
    std::string name, message, hardware_id;
    std::uint32_t n = 0;
    cdr >> level >> name >> message >> hardware_id >> n;
    json values = json::object();
    for (std::uint32_t k = 0; k < n; ++k) {
      std::string key, value;
      cdr >> key >> value;
      values[key] = value;
    }
    status.push_back({{"level", level},
                      {"name", name},
                      {"message", message},
                      {"hardware_id", hardware_id},
                      {"values", values}});
  }
  return {{"status", status}};
}

json cloud(eprosima::fastcdr::Cdr& cdr) {
  std::uint32_t height = 0, width = 0, count = 0;
  cdr >> height >> width >> count;
  json fields = json::array();
  std::vector<std::uint32_t> offsets;
  for (std::uint32_t i = 0; i < count; ++i) {
    std::string name;
    std::uint32_t offset = 0, n = 0;
    std::uint8_t type = 0;
    cdr >> name >> offset >> type >> n;
    fields.push_back({name, offset, type, n});
    offsets.push_back(offset);
  }
  bool big = false, dense = false;
  std::uint32_t point_step = 0, row_step = 0;
  std::vector<std::uint8_t> data;
  cdr >> big >> point_step >> row_step >> data >> dense;
  json points = json::array();
  for (std::uint32_t i = 0; i < width * height; ++i) {
    json point = json::array();
    for (const std::uint32_t offset : offsets) {
      float v;
      std::memcpy(&v, data.data() + i * point_step + offset, 4);
      point.push_back(std::isfinite(v) ? json(v) : json(nullptr));
    }
    points.push_back(point);
  }
  return {{"width", width},           {"height", height},     {"fields", fields},
          {"point_step", point_step}, {"row_step", row_step}, {"is_dense", dense},
          {"points", points}};
}

struct Topic {
  std::string name;
  const char* type;      // the DDS type name
  const char* ros_type;  // as the recordings name it
  fdds::DataReader* reader = nullptr;
};

}  // namespace

int main(int argc, char** argv) {
  if (argc < 4) {
    std::fprintf(stderr, "usage: epipole-fastdds-listener DOMAIN NAMESPACE SECONDS [GRID]\n");
    return 2;
  }
  const int domain = std::stoi(argv[1]);
  const std::string ns = argv[2];
  const int seconds = std::stoi(argv[3]);
  if (argc > 4) grid = std::stoi(argv[4]);
  const auto deadline = epipole::test::ListenClock::now() + std::chrono::seconds(seconds);

  fdds::DomainParticipantFactory* factory = fdds::DomainParticipantFactory::get_instance();
  factory->load_profiles();  // FASTRTPS_DEFAULT_PROFILES_FILE
  fdds::DomainParticipant* participant =
      factory->create_participant(domain, fdds::PARTICIPANT_QOS_DEFAULT);
  if (participant == nullptr) {
    std::fprintf(stderr, "fastdds listener: no participant\n");
    return 1;
  }
  fdds::Subscriber* subscriber = participant->create_subscriber(fdds::SUBSCRIBER_QOS_DEFAULT);
  std::vector<Topic> topics = {
      {ns + "/left/image_rect", "sensor_msgs::msg::dds_::Image_", "sensor_msgs/msg/Image"},
      {ns + "/left/camera_info", "sensor_msgs::msg::dds_::CameraInfo_",
       "sensor_msgs/msg/CameraInfo"},
      {ns + "/depth", "sensor_msgs::msg::dds_::Image_", "sensor_msgs/msg/Image"},
      {ns + "/points", "sensor_msgs::msg::dds_::PointCloud2_", "sensor_msgs/msg/PointCloud2"},
      {"/diagnostics", "diagnostic_msgs::msg::dds_::DiagnosticArray_",
       "diagnostic_msgs/msg/DiagnosticArray"},
  };
  for (Topic& t : topics) {
    fdds::TypeSupport type(new RawType(t.type));
    type.register_type(participant);  // again for a type already there: fine
    fdds::Topic* topic = participant->create_topic("rt" + t.name, t.type, fdds::TOPIC_QOS_DEFAULT);
    fdds::DataReaderQos qos = fdds::DATAREADER_QOS_DEFAULT;
    qos.reliability().kind = fdds::RELIABLE_RELIABILITY_QOS;
    qos.history().kind = fdds::KEEP_LAST_HISTORY_QOS;
    qos.history().depth = 200;
    t.reader = subscriber->create_datareader(topic, qos);
    if (t.reader == nullptr) {
      std::fprintf(stderr, "fastdds listener: no reader of %s\n", t.name.c_str());
      return 1;
    }
  }
  std::vector<std::string> names;
  for (const Topic& t : topics) names.push_back(t.name);
  if (!epipole::test::wait_for_writers(names, deadline, [&](std::size_t i) {
        fdds::SubscriptionMatchedStatus matched;
        return topics[i].reader->get_subscription_matched_status(matched) ==
                   ReturnCode_t::RETCODE_OK &&
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
          RawSample sample;
          fdds::SampleInfo info;
          while (t.reader->take_next_sample(&sample, &info) == ReturnCode_t::RETCODE_OK) {
            any = true;
            if (!info.valid_data) continue;
            Decoder d(sample);
            json m = {{"topic", t.name}, {"type", t.ros_type}};
            const Header h = header(d.cdr);
            if (t.name.ends_with("camera_info")) {
              m.update(camera_info(d.cdr));
            } else if (t.name.ends_with("points")) {
              m.update(cloud(d.cdr));
            } else if (t.name == "/diagnostics") {
              m.update(diagnostics(d.cdr));
            } else {
              m.update(image(d.cdr));
              if (t.name.ends_with("left/image_rect")) ++left_images;
            }
            stamp(m, h);
            messages.push_back(m);
          }
        }
        return any;
      },
      [&] { return left_images > 0; });
  participant->delete_contained_entities();
  factory->delete_participant(participant);
  std::cout << json{{"messages", messages}}.dump() << "\n";
  return left_images > 0 ? 0 : 3;
}
