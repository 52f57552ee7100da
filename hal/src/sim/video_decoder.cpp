// Video files through FFmpeg's libraries: demuxed by libavformat, decoded by libavcodec, each
// frame converted to GRAY8 by libswscale (the luma plane, in full range). Built as the plugin
// libepipole_video.so (video_plugin.hpp), which video_loader.cpp opens when a video is replayed.
#include "video_decoder.hpp"

#include <algorithm>
#include <cstring>
#include <memory>
#include <string>

#include "epipole/core/error.hpp"
#include "video_plugin.hpp"

extern "C" {
#include <libavcodec/avcodec.h>
#include <libavformat/avformat.h>
#include <libavutil/error.h>
#include <libavutil/log.h>
#include <libswscale/swscale.h>
}

namespace epipole::hal {

namespace {

std::string av_error(int code) {
  char text[AV_ERROR_MAX_STRING_SIZE] = {};
  av_strerror(code, text, sizeof text);
  return text;
}

struct FormatClose {
  void operator()(AVFormatContext* c) const { avformat_close_input(&c); }
};
struct CodecFree {
  void operator()(AVCodecContext* c) const { avcodec_free_context(&c); }
};
struct PacketFree {
  void operator()(AVPacket* p) const { av_packet_free(&p); }
};
struct FrameFree {
  void operator()(AVFrame* f) const { av_frame_free(&f); }
};
struct ScaleFree {
  void operator()(SwsContext* s) const { sws_freeContext(s); }
};

class Decoder {
 public:
  Decoder(const std::filesystem::path& file, int limit, const std::function<void(GrayView)>& frame)
      : file_(file), name_(file.string()), limit_(limit), frame_(frame) {}

  int run() {
    std::error_code ec;
    require(std::filesystem::is_regular_file(file_, ec), name_, ": no such file");
    av_log_set_level(AV_LOG_QUIET);  // every failure becomes one Error instead
    AVFormatContext* raw = nullptr;
    if (const int rc = avformat_open_input(&raw, name_.c_str(), nullptr, nullptr); rc < 0) {
      fail(cat("is not a video FFmpeg can read (", av_error(rc), ")"));
    }
    format_.reset(raw);
    // FFmpeg reads a picture as a one-frame video (its image2 and *_pipe demuxers): refused.
    const std::string demuxer = format_->iformat->name;
    if (demuxer == "image2" || (demuxer.size() > 5 && demuxer.ends_with("_pipe"))) {
      fail(cat("is not a video but a picture (FFmpeg reads it as ", demuxer, ")"));
    }
    if (const int rc = avformat_find_stream_info(format_.get(), nullptr); rc < 0) {
      fail(cat("is not a readable video (", av_error(rc), ")"));
    }
    const AVCodec* codec = nullptr;
    stream_ = av_find_best_stream(format_.get(), AVMEDIA_TYPE_VIDEO, -1, -1, &codec, 0);
    if (stream_ == AVERROR_STREAM_NOT_FOUND) fail("has no video stream");
    if (stream_ < 0 || codec == nullptr) fail("has no video stream FFmpeg can decode");
    const AVStream* stream = format_->streams[stream_];
    codec_.reset(avcodec_alloc_context3(codec));
    require(codec_ != nullptr, name_, ": out of memory");
    if (avcodec_parameters_to_context(codec_.get(), stream->codecpar) < 0 ||
        avcodec_open2(codec_.get(), codec, nullptr) < 0) {
      fail(cat("cannot open its ", codec->name, " decoder"));
    }
    packet_.reset(av_packet_alloc());
    decoded_.reset(av_frame_alloc());
    require(packet_ != nullptr && decoded_ != nullptr, name_, ": out of memory");

    while (count_ < limit_) {
      const int rc = av_read_frame(format_.get(), packet_.get());
      if (rc == AVERROR_EOF) break;
      if (rc < 0) fail(cat("a corrupt stream after frame ", count_, " (", av_error(rc), ")"));
      const bool ours = packet_->stream_index == stream_;
      if (ours) send(packet_.get());
      av_packet_unref(packet_.get());
    }
    if (count_ < limit_) send(nullptr);  // drain the decoder
    if (count_ == 0) fail("holds no frame that decodes");
    // A container that states its length (AVI does) and a stream that ends early: truncated.
    if (count_ < limit_ && stream->nb_frames > 0 && count_ < stream->nb_frames) {
      fail(cat("a truncated or corrupt stream: ", count_, " frames decode but the file states ",
               stream->nb_frames));
    }
    return count_;
  }

 private:
  [[noreturn]] void fail(const std::string& what) const { throw Error(cat(name_, ": ", what)); }

  void send(const AVPacket* packet) {
    if (const int rc = avcodec_send_packet(codec_.get(), packet); rc < 0 && rc != AVERROR_EOF) {
      fail(cat("a corrupt stream at frame ", count_, " (", av_error(rc), ")"));
    }
    while (count_ < limit_) {
      const int rc = avcodec_receive_frame(codec_.get(), decoded_.get());
      if (rc == AVERROR(EAGAIN) || rc == AVERROR_EOF) return;
      if (rc < 0) fail(cat("a corrupt stream at frame ", count_, " (", av_error(rc), ")"));
      if ((decoded_->flags & AV_FRAME_FLAG_CORRUPT) != 0 || decoded_->decode_error_flags != 0) {
        fail(cat("a corrupt stream: frame ", count_, " does not decode cleanly"));
      }
      convert();
      av_frame_unref(decoded_.get());
    }
  }

  void convert() {
    const AVFrame& f = *decoded_;
    if (count_ == 0) {
      gray_ = GrayImage(f.width, f.height);
    } else if (f.width != gray_.width() || f.height != gray_.height()) {
      fail(cat("frame ", count_, " is ", f.width, "x", f.height, " but frame 0 is ", gray_.width(),
               "x", gray_.height()));
    }
    scale_.reset(sws_getCachedContext(scale_.release(), f.width, f.height,
                                      static_cast<AVPixelFormat>(f.format), f.width, f.height,
                                      AV_PIX_FMT_GRAY8, SWS_POINT, nullptr, nullptr, nullptr));
    if (!scale_) fail(cat("frames of pixel format ", f.format, " cannot be converted to gray"));
    std::uint8_t* planes[4] = {gray_.view().data(), nullptr, nullptr, nullptr};
    int strides[4] = {static_cast<int>(gray_.stride()), 0, 0, 0};
    if (sws_scale(scale_.get(), f.data, f.linesize, 0, f.height, planes, strides) != f.height) {
      fail(cat("frame ", count_, " cannot be converted to gray"));
    }
    frame_(gray_.view());
    ++count_;
  }

  const std::filesystem::path& file_;
  const std::string name_;
  const int limit_;
  const std::function<void(GrayView)>& frame_;
  std::unique_ptr<AVFormatContext, FormatClose> format_;
  std::unique_ptr<AVCodecContext, CodecFree> codec_;
  std::unique_ptr<AVPacket, PacketFree> packet_;
  std::unique_ptr<AVFrame, FrameFree> decoded_;
  std::unique_ptr<SwsContext, ScaleFree> scale_;
  GrayImage gray_;
  int stream_ = -1;
  int count_ = 0;
};

}  // namespace

int decode_video_gray(const std::filesystem::path& file, int limit,
                      const std::function<void(GrayView)>& frame) {
  require(limit > 0, file.string(), ": the frame limit must be at least 1");
  return Decoder(file, limit, frame).run();
}

}  // namespace epipole::hal

// The plugin's entry point (video_plugin.hpp).
extern "C" __attribute__((visibility("default"))) int epipole_video_decode_gray(
    const char* file, int limit, EpipoleVideoFrame frame, void* context, char* error,
    std::size_t error_size) {
  try {
    return epipole::hal::decode_video_gray(file, limit,
                                           [&](epipole::GrayView view) { frame(context, &view); });
  } catch (const std::exception& e) {
    if (error_size > 0) {
      const std::size_t n = std::min(std::strlen(e.what()), error_size - 1);
      std::memcpy(error, e.what(), n);
      error[n] = '\0';
    }
    return -1;
  }
}
