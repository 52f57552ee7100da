#pragma once

#include <filesystem>
#include <vector>

#include "epipole/core/image.hpp"

namespace epipole::hal {

// Stereo image sets for the simulated cameras, read from files (host builds with image files:
// the epipole_hal_simfiles library). Every failure throws Error naming the file.
struct StereoImages {
  std::vector<GrayImage> left;
  std::vector<GrayImage> right;
};

// Pairs the i-th left file with the i-th right file; all must have one size.
StereoImages load_stereo_pairs(const std::vector<std::filesystem::path>& left_files,
                               const std::vector<std::filesystem::path>& right_files);

// A directory of pairs: files whose names start with "left" and "right", paired in name order
// (left_000.png with right_000.png, ...). A video is replayed the same way, from its frames
// extracted to such files.
StereoImages load_stereo_directory(const std::filesystem::path& directory);

// One left image and the right view synthesised from it at a constant disparity.
StereoImages synthesize_stereo(const std::filesystem::path& left_file, int disparity);

}  // namespace epipole::hal
