#pragma once

#include <filesystem>
#include <vector>

#include "epipole/core/image.hpp"

namespace epipole::hal {

// Stereo image sets for the simulated cameras, read from files (builds with image files; in
// the others the scene loader says so). Every failure throws Error naming the file.
struct StereoImages {
  std::vector<GrayImage> left;
  std::vector<GrayImage> right;
};

// Pairs the i-th left file with the i-th right file; all must have one size.
StereoImages load_stereo_pairs(const std::vector<std::filesystem::path>& left_files,
                               const std::vector<std::filesystem::path>& right_files);

// A directory of pairs: files whose names start with "left" and "right", paired in name order
// (left_000.png with right_000.png, ...).
StereoImages load_stereo_directory(const std::filesystem::path& directory);

// One left image and the right view synthesised from it at a constant disparity.
StereoImages synthesize_stereo(const std::filesystem::path& left_file, int disparity);

// Videos, decoded with FFmpeg's libraries at start-up into memory (nothing is decoded per
// frame). Every frame is converted to 8-bit gray (its luma) and, when `fit` has a size, fitted
// into it as it is decoded (letterbox(), sim_scene.hpp), so only fitted frames are kept.
// A video of more than `max_frames` frames is refused (the error says how many it would take in
// memory); so are a missing file, a file that is not a video or has no video stream, a corrupt
// stream and frames that change size. Builds without FFmpeg throw saying so.
struct VideoOptions {
  int max_frames = 300;
  int fit_width = 0;  // 0: the video's own size
  int fit_height = 0;
};

// True when the file name ends in an extension of video files (.avi, .mp4, .mkv, .mov, .webm,
// .m4v, .mpg, .mpeg, .ts, .ogv, .wmv, .flv, .y4m; any case).
bool is_video_file(const std::filesystem::path& file);

// Every frame of one video, in gray.
std::vector<GrayImage> load_video_gray(const std::filesystem::path& file,
                                       const VideoOptions& options = {});

// Two synchronised recordings, paired frame by frame; the shorter sets the length. The frames
// of both must have one size.
StereoImages load_stereo_videos(const std::filesystem::path& left_file,
                                const std::filesystem::path& right_file,
                                const VideoOptions& options = {});

// One video whose frames hold the left view in their left half and the right view in their
// right half (an even width).
StereoImages load_side_by_side_video(const std::filesystem::path& file,
                                     const VideoOptions& options = {});

// The raw pairs of an MCAP recording (recording_scene.cpp): the sensor_msgs/Image messages of its
// topics .../left/image_raw and .../right/image_raw (mono8, rgb8 or bgr8), paired by stamp, in
// the order recorded; at most `max_frames` of each side. Errors name the file and the message.
StereoImages load_recording(const std::filesystem::path& file, const VideoOptions& options = {});

// Each frame of a video as the left view, the right view synthesised at a constant disparity.
StereoImages synthesize_stereo_video(const std::filesystem::path& file, int disparity,
                                     const VideoOptions& options = {});

}  // namespace epipole::hal
