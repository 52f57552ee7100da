#pragma once

// The detector's boxes, each labelled with its distance, as foxglove_msgs/msg/ImageAnnotations:
// what Foxglove's and Lichtblick's Image panel draws over the rectified left image.
#include <cstdint>
#include <span>
#include <vector>

#include "epipole/firmware/detection_depth.hpp"
#include "epipole/vision/cascade.hpp"
#include "ros/ros_messages.hpp"

namespace epipole::firmware::ros {

MessageType image_annotations_type();

// One closed outline (LINE_LOOP) per box and one label at its top left corner: "1.72 m", or
// "depth unknown" when the box holds too few disparities. The depths are in the calibration's
// units, metres.
void write_detection_annotations(std::vector<std::uint8_t>& out, Time stamp,
                                 std::span<const vision::Detection> detections,
                                 std::span<const DetectionDepth> depths);

}  // namespace epipole::firmware::ros
