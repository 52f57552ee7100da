#pragma once

// OpenCV's stereo calibration files (cv::FileStorage: YAML, XML or JSON) on the host, read and
// written by OpenCV itself. The firmware reads only Epipole's own file (epipole/calib) and
// never links OpenCV.

#include <filesystem>

#include "epipole/calib/calibration.hpp"

namespace epipole::tools {

// Imports OpenCV's stereo calibration output as OpenCV's stereo_calib sample writes it:
// `intrinsics` holds M1 D1 M2 D2, `extrinsics` R T R1 R2 P1 P2 (Q optional: computed from P1
// and P2 when absent); each key is looked for in both files, so one file holding all of them
// works too. Neither file need record the image size: give it, or 0x0 to read
// image_width/image_height from either file. Distortion vectors of 4, 5, 8, 12 or 14
// coefficients are accepted when every coefficient beyond k1 k2 p1 p2 k3 is zero. Anything
// else (unreadable or malformed files, missing keys, wrong sizes, non-finite numbers, an
// unsupported model, an invalid geometry) is an Error naming the file and, where there is one,
// the key and line.
calib::StereoCalibration import_opencv_calibration(const std::filesystem::path& intrinsics,
                                                   const std::filesystem::path& extrinsics,
                                                   int width = 0, int height = 0);

// Writes intrinsics.yml (M1 D1 M2 D2) and extrinsics.yml (R T R1 R2 P1 P2 Q) into `directory`
// (made when missing) with cv::FileStorage, as the stereo_calib sample writes them, plus
// image_width and image_height; each file through a temporary file and a rename. OpenCV
// writes doubles with 17 significant digits, so importing them gives the same calibration.
// Throws Error naming the file.
void export_opencv_calibration(const calib::StereoCalibration& calibration,
                               const std::filesystem::path& directory);

}  // namespace epipole::tools
