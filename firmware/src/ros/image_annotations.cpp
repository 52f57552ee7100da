#include "ros/image_annotations.hpp"

#include <cstdio>
#include <string>

#include "epipole/core/cdr_writer.hpp"
#include "ros/message_schema.hpp"

namespace epipole::firmware::ros {

namespace {

// foxglove_msgs' definitions (the Foxglove schemas' ROS 2 messages), without their comments.
constexpr std::string_view kImageAnnotations =
    "foxglove_msgs/CircleAnnotation[] circles\nfoxglove_msgs/PointsAnnotation[] points\n"
    "foxglove_msgs/TextAnnotation[] texts\n";
constexpr std::string_view kCircleAnnotation =
    "builtin_interfaces/Time timestamp\nfoxglove_msgs/Point2 position\nfloat64 diameter\n"
    "float64 thickness\nfoxglove_msgs/Color fill_color\nfoxglove_msgs/Color outline_color\n";
constexpr std::string_view kPointsAnnotation =
    "builtin_interfaces/Time timestamp\nuint8 UNKNOWN=0\nuint8 POINTS=1\nuint8 LINE_LOOP=2\n"
    "uint8 LINE_STRIP=3\nuint8 LINE_LIST=4\nuint8 type\nfoxglove_msgs/Point2[] points\n"
    "foxglove_msgs/Color outline_color\nfoxglove_msgs/Color[] outline_colors\n"
    "foxglove_msgs/Color fill_color\nfloat64 thickness\n";
constexpr std::string_view kTextAnnotation =
    "builtin_interfaces/Time timestamp\nfoxglove_msgs/Point2 position\nstring text\n"
    "float64 font_size\nfoxglove_msgs/Color text_color\nfoxglove_msgs/Color background_color\n";
constexpr std::string_view kPoint2 = "float64 x\nfloat64 y\n";
constexpr std::string_view kColor = "float64 r\nfloat64 g\nfloat64 b\nfloat64 a\n";

constexpr std::uint8_t kLineLoop = 2;

struct Colour {
  double r, g, b, a;
};
constexpr Colour kBox{1.0, 0.65, 0.17, 1.0};      // the page's orange
constexpr Colour kLabelBack{0.0, 0.0, 0.0, 0.6};  // behind the text
constexpr Colour kWhite{1.0, 1.0, 1.0, 1.0};
constexpr Colour kNone{0.0, 0.0, 0.0, 0.0};

void time(cdr::CdrWriter& w, Time t) {
  w.i32(t.sec);
  w.u32(t.nanosec);
}
void point(cdr::CdrWriter& w, double x, double y) {
  w.f64(x);
  w.f64(y);
}
void colour(cdr::CdrWriter& w, const Colour& c) {
  w.f64(c.r);
  w.f64(c.g);
  w.f64(c.b);
  w.f64(c.a);
}

}  // namespace

MessageType image_annotations_type() {
  static std::string s;
  static const std::string_view text =
      schema(s, kImageAnnotations,
             {{"foxglove_msgs/CircleAnnotation", kCircleAnnotation},
              {"builtin_interfaces/Time", kTime},
              {"foxglove_msgs/Point2", kPoint2},
              {"foxglove_msgs/Color", kColor},
              {"foxglove_msgs/PointsAnnotation", kPointsAnnotation},
              {"foxglove_msgs/TextAnnotation", kTextAnnotation}});
  return {"foxglove_msgs/msg/ImageAnnotations", text};
}

void write_detection_annotations(std::vector<std::uint8_t>& out, Time stamp,
                                 std::span<const vision::Detection> detections,
                                 std::span<const DetectionDepth> depths) {
  cdr::CdrWriter w(out);
  w.u32(0);  // circles
  w.u32(static_cast<std::uint32_t>(detections.size()));
  for (const vision::Detection& d : detections) {
    time(w, stamp);
    w.u8(kLineLoop);
    w.u32(4);
    point(w, d.x, d.y);
    point(w, d.x + d.width, d.y);
    point(w, d.x + d.width, d.y + d.height);
    point(w, d.x, d.y + d.height);
    colour(w, kBox);
    w.u32(0);  // outline_colors
    colour(w, kNone);
    w.f64(2.0);
  }
  w.u32(static_cast<std::uint32_t>(detections.size()));
  for (std::size_t i = 0; i < detections.size(); ++i) {
    const vision::Detection& d = detections[i];
    char label[32] = "depth unknown";
    if (i < depths.size() && depths[i].valid) {
      std::snprintf(label, sizeof label, "%.2f m", depths[i].depth);
    }
    time(w, stamp);
    point(w, d.x, d.y > 16 ? d.y - 16 : d.y);
    w.string(label);
    w.f64(14.0);
    colour(w, kWhite);
    colour(w, kLabelBack);
  }
}

}  // namespace epipole::firmware::ros
