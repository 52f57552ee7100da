#include "epipole/hal/sim_files.hpp"

#include <algorithm>
#include <string>

#include "epipole/core/error.hpp"
#include "epipole/core/image_io.hpp"
#include "epipole/hal/sim.hpp"

namespace epipole::hal {

StereoImages load_stereo_pairs(const std::vector<std::filesystem::path>& left_files,
                               const std::vector<std::filesystem::path>& right_files) {
  require(!left_files.empty() && left_files.size() == right_files.size(),
          "stereo images: ", left_files.size(), " left and ", right_files.size(),
          " right files (must be the same, at least one)");
  StereoImages images;
  for (std::size_t i = 0; i < left_files.size(); ++i) {
    GrayImage left = load_gray(left_files[i]);
    GrayImage right = load_gray(right_files[i]);
    require(same_size(left.view(), right.view()), "stereo images: ", right_files[i].string(),
            " is ", right.width(), "x", right.height(), " but ", left_files[i].string(), " is ",
            left.width(), "x", left.height());
    require(images.left.empty() || same_size(images.left.front().view(), left.view()),
            "stereo images: ", left_files[i].string(), " differs in size from ",
            left_files.front().string());
    images.left.push_back(std::move(left));
    images.right.push_back(std::move(right));
  }
  return images;
}

StereoImages load_stereo_directory(const std::filesystem::path& directory) {
  require(std::filesystem::is_directory(directory), "stereo images: ", directory.string(),
          " is not a directory");
  std::vector<std::filesystem::path> left, right;
  for (const auto& entry : std::filesystem::directory_iterator(directory)) {
    if (!entry.is_regular_file()) continue;
    const std::string name = entry.path().filename().string();
    if (name.rfind("left", 0) == 0) left.push_back(entry.path());
    if (name.rfind("right", 0) == 0) right.push_back(entry.path());
  }
  std::sort(left.begin(), left.end());
  std::sort(right.begin(), right.end());
  require(!left.empty(), "stereo images: no left*/right* files in ", directory.string());
  return load_stereo_pairs(left, right);
}

StereoImages synthesize_stereo(const std::filesystem::path& left_file, int disparity) {
  StereoImages images;
  images.left.push_back(load_gray(left_file));
  images.right.push_back(synthesize_right(images.left.front().view(), disparity));
  return images;
}

}  // namespace epipole::hal
