#pragma once

// The entry point of the video plugin (libepipole_video.so, video_decoder.cpp): FFmpeg's
// libraries are loaded only by a process that replays a video, so the firmware does not depend on
// them (a board's image, the virtual board's initramfs). A C signature: nothing but plain
// pointers crosses the boundary, errors come back as text.
#include <cstddef>

#include "epipole/core/image.hpp"

extern "C" {

// Called with each decoded gray frame; its view is valid during the call only.
using EpipoleVideoFrame = void (*)(void* context, const epipole::GrayView* frame);

// decode_video_gray() of video_decoder.hpp. Returns the frames decoded, or -1 with the error's
// message in `error` (truncated to error_size - 1 bytes).
using EpipoleVideoDecode = int (*)(const char* file, int limit, EpipoleVideoFrame frame,
                                   void* context, char* error, std::size_t error_size);

}  // extern "C"

#define EPIPOLE_VIDEO_PLUGIN_ENTRY "epipole_video_decode_gray"
