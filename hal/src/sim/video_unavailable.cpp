// Builds without FFmpeg's libraries (libavformat, libavcodec, libswscale, libavutil).
#include "epipole/core/error.hpp"
#include "video_decoder.hpp"

namespace epipole::hal {

int decode_video_gray(const std::filesystem::path& file, int /*limit*/,
                      const std::function<void(GrayView)>& /*frame*/) {
  throw Error(cat(file.string(),
                  ": this build cannot read videos (it was built without FFmpeg's libavformat, "
                  "libavcodec, libswscale and libavutil)"));
}

}  // namespace epipole::hal
