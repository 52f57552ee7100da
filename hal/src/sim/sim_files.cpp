#include "sim/sim_files.hpp"

#include <algorithm>
#include <array>
#include <cctype>
#include <string>

#include "epipole/core/error.hpp"
#include "epipole/core/image_io.hpp"
#include "sim/sim_scene.hpp"
#include "video_decoder.hpp"

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

bool is_video_file(const std::filesystem::path& file) {
  std::string ext = file.extension().string();
  for (char& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  static constexpr std::array<const char*, 13> kVideo = {".avi", ".mp4", ".mkv",  ".mov", ".webm",
                                                         ".m4v", ".mpg", ".mpeg", ".ts",  ".ogv",
                                                         ".wmv", ".flv", ".y4m"};
  return std::find(kVideo.begin(), kVideo.end(), ext) != kVideo.end();
}

namespace {

// The frame as kept: fitted into the options' size when it has one.
GrayImage kept(GrayView frame, const VideoOptions& options) {
  if (options.fit_width > 0 && options.fit_height > 0) {
    return letterbox(frame, options.fit_width, options.fit_height);
  }
  return letterbox(frame, frame.width(), frame.height());
}

// Decodes at most max_frames + 1 frames, so that a longer video is seen to be longer.
int decode(const std::filesystem::path& file, const VideoOptions& options,
           const std::function<void(GrayView)>& frame) {
  require(options.max_frames > 0, file.string(), ": max_frames must be at least 1");
  return decode_video_gray(file, options.max_frames + 1, frame);
}

void require_within_limit(std::size_t frames, const VideoOptions& options, GrayView frame,
                          const std::string& what) {
  const std::size_t bytes = static_cast<std::size_t>(frame.width()) * frame.height();
  require(frames <= static_cast<std::size_t>(options.max_frames), what, ": more than ",
          options.max_frames, " frames (max_frames); raise max_frames (each frame of ",
          frame.width(), "x", frame.height(), " takes ", bytes, " bytes per camera) or shorten it");
}

}  // namespace

std::vector<GrayImage> load_video_gray(const std::filesystem::path& file,
                                       const VideoOptions& options) {
  std::vector<GrayImage> frames;
  decode(file, options, [&](GrayView f) { frames.push_back(kept(f, options)); });
  require_within_limit(frames.size(), options, frames.front().view(), file.string());
  return frames;
}

StereoImages load_stereo_videos(const std::filesystem::path& left_file,
                                const std::filesystem::path& right_file,
                                const VideoOptions& options) {
  StereoImages images;
  int left_width = 0, left_height = 0;
  decode(left_file, options, [&](GrayView f) {
    left_width = f.width();
    left_height = f.height();
    images.left.push_back(kept(f, options));
  });
  decode(right_file, options, [&](GrayView f) {
    require(f.width() == left_width && f.height() == left_height,
            "stereo videos: ", right_file.string(), " is ", f.width(), "x", f.height(), " but ",
            left_file.string(), " is ", left_width, "x", left_height);
    if (images.right.size() < images.left.size()) images.right.push_back(kept(f, options));
  });
  images.left.resize(images.right.size());  // the shorter sets the length
  require_within_limit(images.left.size(), options, images.left.front().view(),
                       cat("stereo videos ", left_file.string(), " and ", right_file.string()));
  return images;
}

StereoImages load_side_by_side_video(const std::filesystem::path& file,
                                     const VideoOptions& options) {
  StereoImages images;
  decode(file, options, [&](GrayView f) {
    require(f.width() % 2 == 0, file.string(), ": a side-by-side video needs an even width, not ",
            f.width(), " (", f.width(), "x", f.height(), ")");
    const int half = f.width() / 2;
    images.left.push_back(kept(f.sub(0, 0, half, f.height()), options));
    images.right.push_back(kept(f.sub(half, 0, half, f.height()), options));
  });
  require_within_limit(images.left.size(), options, images.left.front().view(), file.string());
  return images;
}

StereoImages synthesize_stereo_video(const std::filesystem::path& file, int disparity,
                                     const VideoOptions& options) {
  StereoImages images;
  images.left = load_video_gray(file, options);
  for (const GrayImage& left : images.left) {
    images.right.push_back(synthesize_right(left.view(), disparity));
  }
  return images;
}

}  // namespace epipole::hal
