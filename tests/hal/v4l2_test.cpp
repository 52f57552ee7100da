#include <gtest/gtest.h>

#include <linux/videodev2.h>

#include <functional>
#include <string>
#include <utility>
#include <vector>

#include "epipole/core/error.hpp"
#include "epipole/hal/device_missing.hpp"
#include "epipole/hal/registry.hpp"
#include "v4l2/v4l2_camera.hpp"

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

// A UVC camera as `v4l2-ctl -L` lists one: auto_exposure (menu 0..3 offering 1 manual and 3
// aperture priority), exposure_time_absolute 3..2047, gain 0..255, no automatic gain.
V4l2ExposureControls uvc_camera() {
  V4l2ExposureControls c;
  c.exposure_auto = {true, 0, 3,
                     (1u << V4L2_EXPOSURE_MANUAL) | (1u << V4L2_EXPOSURE_APERTURE_PRIORITY)};
  c.exposure_absolute = {true, 3, 2047, 0};
  c.gain = {true, 0, 255, 0};
  return c;
}

std::vector<std::pair<std::uint32_t, std::int32_t>> controls_of(const V4l2ControlPlan& plan) {
  std::vector<std::pair<std::uint32_t, std::int32_t>> out;
  for (int i = 0; i < plan.count; ++i) {
    out.emplace_back(plan.controls[static_cast<std::size_t>(i)].id,
                     plan.controls[static_cast<std::size_t>(i)].value);
  }
  return out;
}

std::string plan_error(Nanoseconds exposure, double gain, const V4l2ExposureControls& c,
                       bool starting = false) {
  try {
    plan_exposure_controls("/dev/video4", exposure, gain, c, starting);
  } catch (const Error& e) {
    return e.what();
  }
  return "no error";
}

TEST(V4l2Controls, ManualAndAutomaticExposureAndGain) {
  using C = std::vector<std::pair<std::uint32_t, std::int32_t>>;
  const V4l2ExposureControls uvc = uvc_camera();
  // 4 ms: manual mode first, then 40 x 100 us; gain in the driver's units.
  EXPECT_EQ(controls_of(plan_exposure_controls("/dev/video4", 4'000'000, 12.4, uvc, false)),
            (C{{V4L2_CID_EXPOSURE_AUTO, V4L2_EXPOSURE_MANUAL},
               {V4L2_CID_EXPOSURE_ABSOLUTE, 40},
               {V4L2_CID_GAIN, 12}}));
  // 0.33 ms rounds to 3 units; automatic exposure on a UVC camera is aperture priority.
  EXPECT_EQ(controls_of(plan_exposure_controls("/dev/video4", 330'000, 1.0, uvc, false)),
            (C{{V4L2_CID_EXPOSURE_AUTO, V4L2_EXPOSURE_MANUAL},
               {V4L2_CID_EXPOSURE_ABSOLUTE, 3},
               {V4L2_CID_GAIN, 1}}));
  // At start-up, automatic gain on a camera without V4L2_CID_AUTOGAIN leaves the gain alone.
  EXPECT_EQ(controls_of(plan_exposure_controls("/dev/video4", 0, 0.0, uvc, true)),
            (C{{V4L2_CID_EXPOSURE_AUTO, V4L2_EXPOSURE_APERTURE_PRIORITY}}));
  // A sensor driver: fully automatic mode, automatic gain, no exposure menu.
  V4l2ExposureControls sensor;
  sensor.exposure_auto = {true, 0, 1, 0b11};
  sensor.exposure_absolute = {true, 1, 100'000, 0};
  sensor.autogain = {true, 0, 1, 0};
  sensor.gain = {true, 16, 248, 0};
  EXPECT_EQ(controls_of(plan_exposure_controls("/dev/video0", 0, 0.0, sensor, false)),
            (C{{V4L2_CID_EXPOSURE_AUTO, V4L2_EXPOSURE_AUTO}, {V4L2_CID_AUTOGAIN, 1}}));
  EXPECT_EQ(controls_of(plan_exposure_controls("/dev/video0", 10'000'000, 32.0, sensor, false)),
            (C{{V4L2_CID_EXPOSURE_AUTO, V4L2_EXPOSURE_MANUAL},
               {V4L2_CID_EXPOSURE_ABSOLUTE, 100},
               {V4L2_CID_AUTOGAIN, 0},
               {V4L2_CID_GAIN, 32}}));
  sensor.exposure_auto = {};
  EXPECT_EQ(controls_of(plan_exposure_controls("/dev/video0", 10'000'000, 0.0, sensor, false)),
            (C{{V4L2_CID_EXPOSURE_ABSOLUTE, 100}, {V4L2_CID_AUTOGAIN, 1}}));
  EXPECT_STREQ(v4l2_control_name(V4L2_CID_AUTOGAIN), "V4L2_CID_AUTOGAIN");
}

TEST(V4l2Controls, MissingControlsAndValuesOutOfRangeNameDeviceAndSetting) {
  const V4l2ExposureControls uvc = uvc_camera();
  EXPECT_NE(plan_error(0, 0.0, uvc)
                .find("/dev/video4: automatic gain: the device has no "
                      "V4L2_CID_AUTOGAIN control"),
            std::string::npos)
      << plan_error(0, 0.0, uvc);
  EXPECT_NE(plan_error(1'000'000'000, 1.0, uvc)
                .find("/dev/video4: exposure 1000000 us is outside the device's 3..2047 x 100 us"),
            std::string::npos)
      << plan_error(1'000'000'000, 1.0, uvc);
  EXPECT_NE(plan_error(100'000, 1.0, uvc).find("exposure 100 us is outside"), std::string::npos)
      << "1 unit is below the minimum of 3";
  EXPECT_NE(plan_error(4'000'000, 300.0, uvc)
                .find("/dev/video4: gain 300 is outside the device's 0..255"),
            std::string::npos)
      << plan_error(4'000'000, 300.0, uvc);
  V4l2ExposureControls none;
  EXPECT_NE(plan_error(4'000'000, 0.0, none, true)
                .find("/dev/video4: exposure 4000 us: the device has no "
                      "V4L2_CID_EXPOSURE_ABSOLUTE control"),
            std::string::npos)
      << plan_error(4'000'000, 0.0, none, true);
  EXPECT_NE(plan_error(0, 2.0, none, true).find("gain 2: the device has no V4L2_CID_GAIN"),
            std::string::npos);
  EXPECT_NE(plan_error(0, 0.0, none)
                .find("automatic exposure: the device has no "
                      "V4L2_CID_EXPOSURE_AUTO control"),
            std::string::npos)
      << plan_error(0, 0.0, none);
  EXPECT_EQ(plan_exposure_controls("/dev/video4", 0, 0.0, none, true).count, 0)
      << "at start-up automatic leaves a device without the controls as it is";
  V4l2ExposureControls manual_only = uvc;
  manual_only.exposure_auto.menu = 1u << V4L2_EXPOSURE_MANUAL;
  EXPECT_NE(plan_error(0, 1.0, manual_only).find("offers no automatic mode"), std::string::npos);
  manual_only.exposure_auto.menu = 1u << V4L2_EXPOSURE_APERTURE_PRIORITY;
  EXPECT_NE(plan_error(4'000'000, 1.0, manual_only).find("has no manual mode"), std::string::npos);
}

TEST(V4l2Camera, MissingDeviceAndNonCameraAreNamed) {
  CameraConfig config;
  config.device = "/dev/video-epipole-missing";
  // Not there: made all the same (a camera slower than the firmware at boot is waited for);
  // start() and reopen() say it is missing.
  V4l2Camera late(config);
  EXPECT_FALSE(late.streaming());
  for (const auto& attempt : {std::function<void()>([&] { late.start(); }),
                              std::function<void()>([&] { late.reopen(); })}) {
    try {
      attempt();
      ADD_FAILURE() << "a missing device cannot start";
    } catch (const DeviceMissing& e) {
      const std::string m = e.what();
      EXPECT_NE(m.find("/dev/video-epipole-missing: not there"), std::string::npos) << m;
    }
  }
  EXPECT_EQ(late.acquire(0).status, AcquireStatus::device_lost);
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
