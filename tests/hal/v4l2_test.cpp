#include <gtest/gtest.h>

#include <linux/videodev2.h>

#include <string>
#include <vector>

#include "epipole/core/error.hpp"
#include "epipole/hal/registry.hpp"
#include "epipole/hal/v4l2_camera.hpp"

namespace epipole::hal {
namespace {

TEST(V4l2Formats, FourccsRoundTrip) {
  for (const PixelFormat f : {PixelFormat::grey, PixelFormat::y10, PixelFormat::y16,
                              PixelFormat::yuyv, PixelFormat::nv12, PixelFormat::yu12}) {
    EXPECT_EQ(pixel_format_of_fourcc(fourcc_of(f)), f) << to_string(f);
  }
  EXPECT_EQ(fourcc_of(PixelFormat::yu12), V4L2_PIX_FMT_YUV420);
  EXPECT_FALSE(pixel_format_of_fourcc(V4L2_PIX_FMT_MJPEG).has_value());
  EXPECT_TRUE(is_zero_copy(PixelFormat::nv12));
  EXPECT_FALSE(is_zero_copy(PixelFormat::yuyv));
}

TEST(V4l2Formats, ChoiceTakesTheRequestedThenZeroCopy) {
  const std::vector<std::uint32_t> usb = {V4L2_PIX_FMT_MJPEG, V4L2_PIX_FMT_YUYV};
  EXPECT_EQ(choose_format(PixelFormat::grey, usb), PixelFormat::yuyv);
  const std::vector<std::uint32_t> csi = {V4L2_PIX_FMT_Y10, V4L2_PIX_FMT_GREY, V4L2_PIX_FMT_Y16};
  EXPECT_EQ(choose_format(PixelFormat::y10, csi), PixelFormat::y10);
  EXPECT_EQ(choose_format(PixelFormat::yuyv, csi), PixelFormat::grey);
  const std::vector<std::uint32_t> isp = {V4L2_PIX_FMT_YUYV, V4L2_PIX_FMT_NV12};
  EXPECT_EQ(choose_format(PixelFormat::grey, isp), PixelFormat::nv12);
  const std::vector<std::uint32_t> none = {V4L2_PIX_FMT_MJPEG};
  EXPECT_FALSE(choose_format(PixelFormat::grey, none).has_value());
}

TEST(V4l2Formats, TimestampFlags) {
  EXPECT_EQ(timestamp_clock(V4L2_BUF_FLAG_TIMESTAMP_MONOTONIC | V4L2_BUF_FLAG_MAPPED),
            ClockId::monotonic);
  EXPECT_EQ(timestamp_clock(V4L2_BUF_FLAG_TIMESTAMP_COPY), ClockId::other);
  EXPECT_EQ(timestamp_clock(V4L2_BUF_FLAG_TIMESTAMP_UNKNOWN), ClockId::other);
}

TEST(V4l2Buffers, ErrorFlaggedAndShortBuffersAreCorrupt) {
  const std::size_t need = plane_bytes(PixelFormat::y16, 6, 4, 16);
  EXPECT_EQ(need, 16u * 3 + 12);
  const std::uint32_t done = V4L2_BUF_FLAG_DONE | V4L2_BUF_FLAG_TIMESTAMP_MONOTONIC;
  EXPECT_EQ(buffer_status(done, need, 4096, need), AcquireStatus::ok);
  EXPECT_EQ(buffer_status(done, 0, 4096, need), AcquireStatus::ok) << "0: the whole buffer";
  EXPECT_EQ(buffer_status(done | V4L2_BUF_FLAG_ERROR, need, 4096, need), AcquireStatus::corrupt);
  EXPECT_EQ(buffer_status(done, need - 1, 4096, need), AcquireStatus::corrupt);
  EXPECT_EQ(buffer_status(done, 0, need - 1, need), AcquireStatus::corrupt) << "mapped too small";
  EXPECT_EQ(buffer_status(done, 8192, need - 1, need), AcquireStatus::corrupt)
      << "bytesused beyond the mapping is clamped to it";
}

TEST(V4l2Convert, ZeroCopyFormatsViewTheBuffer) {
  const int w = 6, h = 4;
  const std::size_t bpl = 8;  // padded rows
  std::vector<std::uint8_t> nv12(bpl * h * 3 / 2);
  for (std::size_t i = 0; i < nv12.size(); ++i) nv12[i] = static_cast<std::uint8_t>(i);
  for (const PixelFormat f : {PixelFormat::grey, PixelFormat::nv12, PixelFormat::yu12}) {
    const GrayView v = gray_view(f, nv12.data(), nv12.size(), w, h, bpl, {});
    EXPECT_EQ(v.data(), nv12.data());
    EXPECT_EQ(v.stride(), 8);
    EXPECT_EQ(v(5, 3), 3 * 8 + 5);
  }
}

TEST(V4l2Convert, Y16Y10AndYuyvIntoTheScratchBuffer) {
  const int w = 3, h = 2;
  GrayImage scratch(w, h);
  // Y16: samples 0x1234, 0xff00, 0x00ff per row, little endian, 8 bytes per line.
  const std::vector<std::uint8_t> y16 = {0x34, 0x12, 0x00, 0xff, 0xff, 0x00, 0,
                                         0,    0x34, 0x12, 0x00, 0xff, 0xff, 0x00};
  GrayView v = gray_view(PixelFormat::y16, y16.data(), y16.size(), w, h, 8, scratch.view());
  EXPECT_EQ(v.data(), scratch.view().data());
  EXPECT_EQ(v(0, 1), 0x12);
  EXPECT_EQ(v(1, 0), 0xff);
  EXPECT_EQ(v(2, 0), 0x00);
  // Y10: 1023 -> 255, 512 -> 128, 3 -> 0.
  const std::vector<std::uint8_t> y10 = {0xff, 0x03, 0x00, 0x02, 0x03, 0x00,
                                         0xff, 0x03, 0x00, 0x02, 0x03, 0x00};
  v = gray_view(PixelFormat::y10, y10.data(), y10.size(), w, h, 6, scratch.view());
  EXPECT_EQ(v(0, 0), 255);
  EXPECT_EQ(v(1, 1), 128);
  EXPECT_EQ(v(2, 1), 0);
  // YUYV: Y0 U Y1 V ... (width 4: even).
  GrayImage scratch4(4, 1);
  const std::vector<std::uint8_t> yuyv = {10, 128, 20, 129, 30, 130, 40, 131};
  v = gray_view(PixelFormat::yuyv, yuyv.data(), yuyv.size(), 4, 1, 8, scratch4.view());
  EXPECT_EQ(v(0, 0), 10);
  EXPECT_EQ(v(1, 0), 20);
  EXPECT_EQ(v(3, 0), 40);
}

TEST(V4l2Convert, TruncatedBuffersAndBadGeometryAreErrors) {
  std::vector<std::uint8_t> data(100);
  GrayImage scratch(10, 10);
  EXPECT_THROW(gray_view(PixelFormat::grey, data.data(), data.size(), 10, 11, 10, {}), Error);
  EXPECT_THROW(gray_view(PixelFormat::grey, data.data(), data.size(), 10, 10, 9, {}), Error);
  EXPECT_THROW(gray_view(PixelFormat::y16, data.data(), data.size(), 10, 5, 20, scratch.view()),
               Error)
      << "scratch of the wrong size";
  EXPECT_NO_THROW(gray_view(PixelFormat::grey, data.data(), data.size(), 10, 10, 10, {}));
}

TEST(V4l2Camera, MissingDeviceAndNonCameraAreNamed) {
  CameraConfig config;
  config.device = "/dev/video-epipole-missing";
  try {
    V4l2Camera camera(config);
    FAIL();
  } catch (const Error& e) {
    const std::string m = e.what();
    EXPECT_NE(m.find("/dev/video-epipole-missing"), std::string::npos) << m;
    EXPECT_NE(m.find("cannot open"), std::string::npos) << m;
  }
  config.device = "/dev/null";
  try {
    auto camera = BackendRegistry::builtin().create_camera("v4l2", config);
    FAIL();
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("/dev/null: not a V4L2 device"), std::string::npos)
        << e.what();
  }
  config.width = 0;
  try {
    V4l2Camera camera(config);
    FAIL();
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("size 0x480"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace epipole::hal
