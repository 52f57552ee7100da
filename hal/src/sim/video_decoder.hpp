#pragma once

#include <filesystem>
#include <functional>

#include "epipole/core/image.hpp"

namespace epipole::hal {

// Decodes a video file's frames in order, each converted to 8-bit gray (its luma), and calls
// `frame` with each, at most `limit` of them; returns how many it decoded. Throws Error naming
// the file: missing, not a video, no video stream, a corrupt or truncated stream, frames that
// change size; builds without FFmpeg throw saying so (video_decoder.cpp, video_unavailable.cpp).
int decode_video_gray(const std::filesystem::path& file, int limit,
                      const std::function<void(GrayView)>& frame);

}  // namespace epipole::hal
