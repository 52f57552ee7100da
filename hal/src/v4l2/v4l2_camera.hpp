#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "epipole/core/image.hpp"
#include "epipole/hal/camera.hpp"
#include "epipole/hal/unique_fd.hpp"

namespace epipole::hal {

// --- The device-independent logic of the V4L2 backend (tested without a device; the gray
// view of a buffer is gray_view() in camera.hpp) ---

// The V4L2 fourcc of a pixel format (V4L2_PIX_FMT_GREY, _Y10, _Y16, _YUYV, _NV12, _YUV420).
std::uint32_t fourcc_of(PixelFormat format);
std::optional<PixelFormat> pixel_format_of_fourcc(std::uint32_t fourcc);
// The format to ask for: the requested one when the device offers it, else the best offered
// one (zero-copy formats first: grey, nv12, yu12, then y16, y10, yuyv); nullopt when the device
// offers none of them.
std::optional<PixelFormat> choose_format(PixelFormat requested,
                                         std::span<const std::uint32_t> offered_fourccs);
// The clock a buffer's timestamp is on, from its V4L2_BUF_FLAG_TIMESTAMP_* flags.
ClockId timestamp_clock(std::uint32_t buffer_flags);
// What a dequeued buffer is: ok, or corrupt when the driver flagged it (V4L2_BUF_FLAG_ERROR)
// or it holds fewer than `needed` bytes (bytesused 0 means the whole mapped length).
AcquireStatus buffer_status(std::uint32_t buffer_flags, std::size_t bytes_used, std::size_t length,
                            std::size_t needed);

// What a device says about one of its controls (VIDIOC_QUERYCTRL; menus: VIDIOC_QUERYMENU).
struct V4l2ControlInfo {
  bool present = false;  // offered and not disabled
  std::int32_t minimum = 0, maximum = 0;
  std::uint64_t menu = 0;  // a menu control: bit i set when item i is offered
};
// The controls exposure and gain are set with.
struct V4l2ExposureControls {
  V4l2ControlInfo exposure_auto;      // V4L2_CID_EXPOSURE_AUTO (menu)
  V4l2ControlInfo exposure_absolute;  // V4L2_CID_EXPOSURE_ABSOLUTE, in 100 us
  V4l2ControlInfo autogain;           // V4L2_CID_AUTOGAIN (boolean)
  V4l2ControlInfo gain;               // V4L2_CID_GAIN, in the driver's units
};
struct V4l2ControlValue {
  std::uint32_t id = 0;
  std::int32_t value = 0;
};
struct V4l2ControlPlan {
  std::array<V4l2ControlValue, 4> controls{};
  int count = 0;
};
// The controls to set, in order, for an exposure and a gain (0: automatic). Manual exposure:
// V4L2_CID_EXPOSURE_AUTO to manual (when the device has it), then V4L2_CID_EXPOSURE_ABSOLUTE
// (rounded to 100 us, at least 1); automatic: V4L2_CID_EXPOSURE_AUTO to auto, else aperture
// priority (UVC cameras offer only that). Manual gain: V4L2_CID_AUTOGAIN off (when the device
// has it), then V4L2_CID_GAIN (rounded); automatic: V4L2_CID_AUTOGAIN on. Throws Error naming
// the device and the setting for a control the device lacks or a value outside its range; at
// start-up (`starting`), automatic on a device without the automatic control leaves it as it is.
V4l2ControlPlan plan_exposure_controls(const std::string& device, Nanoseconds exposure, double gain,
                                       const V4l2ExposureControls& controls, bool starting);
// "V4L2_CID_EXPOSURE_AUTO" and the like, for messages.
const char* v4l2_control_name(std::uint32_t id);

// --- The backend ---

// A V4L2 capture device (linux/videodev2.h only): single- or multi-planar, mmap streaming,
// DQBUF with a poll timeout. Opening and format errors throw Error naming the device and the
// setting; a device node that is not there is no error until start(), which throws
// DeviceMissing (as reopen() does while it is gone); acquire()/release() never throw or
// allocate.
class V4l2Camera final : public CameraSource {
 public:
  explicit V4l2Camera(CameraConfig config);
  ~V4l2Camera() override;
  V4l2Camera(const V4l2Camera&) = delete;
  V4l2Camera& operator=(const V4l2Camera&) = delete;

  const std::string& name() const override { return name_; }
  const CameraConfig& config() const override { return config_; }
  void start() override;
  void stop() override;
  bool streaming() const override { return streaming_; }
  AcquireResult acquire(Nanoseconds timeout) override;
  void release(const Frame& frame) override;
  std::size_t working_set_bytes() const override;
  std::optional<Nanoseconds> shortest_frame_period() const override { return shortest_period_; }
  void reopen() override;
  // Sets the controls of plan_exposure_controls() (the ones used at start-up) at once.
  void set_exposure(Nanoseconds exposure, double gain) override;

  PixelFormat negotiated_format() const { return format_; }
  bool multiplanar() const { return multiplanar_; }

 private:
  struct Buffer {
    void* data = nullptr;
    std::size_t length = 0;
  };
  void open_device();
  void negotiate();
  void open_and_negotiate();
  V4l2ControlInfo query_control(std::uint32_t id) const;
  void apply_exposure(Nanoseconds exposure, double gain, bool starting);
  void close_device();
  [[noreturn]] void fail(const char* what, int error) const;

  CameraConfig config_;
  std::string name_;
  std::optional<Nanoseconds> shortest_period_;  // VIDIOC_ENUM_FRAMEINTERVALS, when it answers
  UniqueFd fd_;
  bool multiplanar_ = false;
  bool streaming_ = false;
  PixelFormat format_ = PixelFormat::grey;
  std::size_t bytes_per_line_ = 0;
  std::vector<Buffer> buffers_;
  std::vector<GrayImage> scratch_;
  std::uint32_t generation_ = 0;
};

}  // namespace epipole::hal
