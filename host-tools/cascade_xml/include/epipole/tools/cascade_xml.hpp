#pragma once

// OpenCV's cascade XML on the host (the host tool, the fuzzers, tests). The firmware loads the
// compiled binary instead (vision::CascadeModel::from_binary) and needs no XML library.

#include <filesystem>
#include <string_view>

#include "epipole/vision/cascade_model.hpp"

namespace epipole::tools {

// Reads a cascade in the format of OpenCV's traincascade (<cascade> with stageType BOOST,
// featureType HAAR or LBP, stages of weak classifiers as stumps or trees, Haar features with
// tilted ones, LBP features with 256 categories) exactly as cv::CascadeClassifier reads it:
// numbers to double, then to float; stage thresholds minus 1e-5 in float. Malformed XML, the
// old "opencv-haar-classifier" format, unknown or unsupported feature types and every
// inconsistency throw Error("SOURCE: line N: ...").
vision::CascadeModel parse_cascade_xml(std::string_view text, std::string_view source);

// A cascade file, OpenCV XML or Epipole's compiled binary, told apart by its first bytes.
// Errors name the file.
vision::CascadeModel load_cascade(const std::filesystem::path& file);

}  // namespace epipole::tools
