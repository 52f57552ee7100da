#pragma once

#include <condition_variable>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <mutex>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "epipole/core/image.hpp"
#include "epipole/hal/camera.hpp"

namespace epipole::hal {

// --- The libcamera-independent logic of the libcamera backend (built and tested everywhere) ---

// How the first plane of a libcamera format holds its samples.
enum class LibcameraLayout {
  r8,         // 8-bit mono
  r10,        // 10-bit mono in little-endian 16-bit words
  r10_csi2p,  // 10-bit mono, MIPI CSI-2 packed: 4 pixels in 5 bytes (4 high bytes, then the lsbs)
  r16,        // 16-bit mono, little endian
  yuyv,       // packed 4:2:2, Y0 U Y1 V
  nv12,       // 4:2:0, the luma plane first
  yuv420,     // 4:2:0 three planes, the luma plane first
  rgb888,     // 24-bit, bytes B, G, R (DRM's RGB888)
  bgr888,     // 24-bit, bytes R, G, B (DRM's BGR888)
};

// One libcamera pixel format the backend can turn into an 8-bit gray plane: its DRM fourcc and
// modifier (as libcamera::PixelFormat holds them), its libcamera name and the CameraConfig
// format that asks for it (RGB formats: none; they are taken only when nothing better is offered,
// as vimc offers nothing else).
struct LibcameraFormat {
  LibcameraLayout layout;
  const char* name;
  std::uint32_t fourcc;
  std::uint64_t modifier;
  bool requestable;
  PixelFormat format;  // meaningful when requestable
};

struct LibcameraFormatCode {
  std::uint32_t fourcc = 0;
  std::uint64_t modifier = 0;
};

// Every format of the backend, in order of preference when the requested one is not offered:
// zero-copy first (R8, NV12, YUV420), then R16, R10, R10_CSI2P, YUYV, RGB888, BGR888.
std::span<const LibcameraFormat> libcamera_formats();
// The entry of a fourcc and modifier; nullptr for a format the backend cannot use.
const LibcameraFormat* find_libcamera_format(LibcameraFormatCode code);
// The format to configure: the requested one when offered (y10: R10, else R10_CSI2P), else the
// most preferred one offered; nullptr when none is.
const LibcameraFormat* choose_libcamera_format(PixelFormat requested,
                                               std::span<const LibcameraFormatCode> offered);
bool is_zero_copy(LibcameraLayout layout);
// The bytes of one row of the first plane.
std::size_t row_bytes(LibcameraLayout layout, int width);
// The gray view of a captured first plane: a view into `data` for zero-copy layouts, else
// converted into `scratch` (width x height). Throws Error when `bytes` or `stride` are too small.
GrayView gray_view(LibcameraLayout layout, const std::uint8_t* data, std::size_t bytes, int width,
                   int height, std::size_t stride, MutableGrayView scratch);

// The camera CameraConfig::device names: a libcamera camera id, else a decimal index (from 0, in
// the order libcamera lists them; ids are stable across boots, indices may not be). Throws
// DeviceMissing naming the device and listing the cameras found: a camera that is not listed yet
// (a USB camera at boot) is waited for.
std::size_t select_camera(std::string_view device, std::span<const std::string> ids);
// "0: <id>, 1: <id>" or "none", for errors.
std::string list_cameras(std::span<const std::string> ids);

// Exposure and gain: what the camera states about its controls (ControlInfoMap), and the
// controls that set them (on Camera::start(), or on the next request queued).
struct LibcameraControlRange {
  bool present = false;
  bool bounded = false;  // the camera states min and max
  double min = 0.0, max = 0.0;
};
struct LibcameraExposureLimits {
  LibcameraControlRange exposure_time;  // ExposureTime, in us
  LibcameraControlRange analogue_gain;  // AnalogueGain, a multiplier
  bool ae_enable = false;               // AeEnable (what turns the AE on before libcamera 0.5)
  bool exposure_time_mode = false;      // ExposureTimeMode (libcamera 0.5 on)
  bool analogue_gain_mode = false;      // AnalogueGainMode (libcamera 0.5 on)
};
// The controls to send; those not set are not sent.
struct LibcameraExposureControls {
  std::optional<std::int32_t> exposure_time_us;
  std::optional<float> analogue_gain;
  std::optional<bool> ae_enable;
  std::optional<bool> exposure_time_manual;  // ExposureTimeMode manual (true) or auto (false)
  std::optional<bool> analogue_gain_manual;  // AnalogueGainMode
};
// The controls for an exposure and a gain (0: automatic). A manual value is ExposureTime (us,
// at least 1) or AnalogueGain, within the range the camera states. With the mode controls
// (`modes`: libcamera 0.5 on) each value's mode is set manual or auto; before 0.5 AeEnable is
// off when both are manual and on otherwise (a manual value set then fixes its half). Throws Error
// naming the device, the camera and the setting for a control the camera lacks or a value
// outside its range; at start-up (`starting`) automatic on a camera without the control that
// turns it on leaves the camera as it is.
LibcameraExposureControls plan_libcamera_exposure(const std::string& device,
                                                  const std::string& camera_id,
                                                  Nanoseconds exposure, double gain,
                                                  const LibcameraExposureLimits& limits, bool modes,
                                                  bool starting);

// One request libcamera completed, as its completion thread hands it over.
struct RequestCompletion {
  int slot = -1;                 // the request's index in the ring
  std::uint32_t generation = 0;  // the stream the request belongs to (start() gives it)
  bool cancelled = false;        // Request::RequestCancelled (the camera is stopping)
  bool damaged = false;          // FrameMetadata::FrameError
  std::uint32_t sequence = 0;    // FrameMetadata::sequence
  Nanoseconds timestamp = 0;     // SensorTimestamp (CLOCK_MONOTONIC), else the buffer's
  std::size_t bytes_used = 0;    // of the first plane; 0: unknown
};

// The hand-over between libcamera's completion thread and acquire(): a fixed ring of request
// slots, each queued (with the camera), ready (completed, waiting for acquire), lent (a Frame)
// or idle; completions are handed out in the order they came. A mutex and a condition variable;
// after start() nothing allocates.
class RequestRing {
 public:
  enum class Wait { ok, timeout, lost };

  // Sizes the ring for `slots` requests, all queued; returns the new generation (allocates).
  std::uint32_t start(int slots);
  // Forgets every slot and bumps the generation (a Frame still lent is then stale).
  void stop();
  // Completion thread. False (ignored) for another generation, an unknown slot or one not queued.
  bool complete(const RequestCompletion& completion);
  // Any thread: the camera is gone; wait() reports lost (after what is ready) until start().
  void lose();
  // Waits at most `timeout` for the oldest ready completion and lends its slot.
  Wait wait(Nanoseconds timeout, RequestCompletion& completion);
  // Gives a lent slot back: true when it was lent in this generation (it is then queued and the
  // caller queues its request again); false for stale, unknown or not lent slots.
  bool give_back(int slot, std::uint32_t generation);

  std::uint32_t generation() const;
  int slots() const;
  int queued() const;
  int ready() const;
  int lent() const;

 private:
  enum class State : std::uint8_t { idle, queued, ready, lent };
  int count(State state) const;

  mutable std::mutex mutex_;
  std::condition_variable changed_;
  std::vector<State> states_;
  std::vector<RequestCompletion> completions_;
  std::vector<int> order_;  // ready slots, oldest first (a ring)
  std::size_t head_ = 0, size_ = 0;
  std::uint32_t generation_ = 0;
  bool running_ = false;
  bool lost_ = false;
};

// The mapped first plane of one frame buffer.
struct MappedPlane {
  const std::uint8_t* data = nullptr;
  std::size_t length = 0;
};

// The acquire/release half of the backend, without libcamera: the request ring, the mapped
// planes, one conversion buffer per request for layouts that are not zero-copy, and what a
// completion becomes (a frame, a corrupt frame, a cancelled request queued again). The camera
// queues a request again through the Requeuer. Sized at start(); acquire() and release() never
// allocate or throw.
class LibcameraStream {
 public:
  class Requeuer {
   public:
    // Queues the request of `slot` again (Request::reuse + Camera::queueRequest); false when
    // the camera refused it.
    virtual bool requeue(int slot) = 0;

   protected:
    ~Requeuer() = default;
  };

  // Throws Error naming `device` when a plane cannot hold the geometry. Returns the generation
  // the requests of this stream carry.
  std::uint32_t start(const std::string& device, const LibcameraFormat& format, int width,
                      int height, std::size_t stride, std::span<const MappedPlane> planes,
                      Requeuer& requeuer);
  void stop();
  bool streaming() const { return requeuer_ != nullptr; }
  RequestRing& ring() { return ring_; }

  AcquireResult acquire(Nanoseconds timeout);
  void release(const Frame& frame);

 private:
  void requeue(int slot, std::uint32_t generation);

  RequestRing ring_;
  Requeuer* requeuer_ = nullptr;
  LibcameraLayout layout_ = LibcameraLayout::r8;
  int width_ = 0, height_ = 0;
  std::size_t stride_ = 0;
  std::size_t needed_ = 0;
  std::vector<MappedPlane> planes_;
  std::vector<GrayImage> scratch_;
};

// --- The backend (built when libcamera is found) ---

// A camera through libcamera (Debian bookworm: 0.0.3; newer versions: docs/hal.md): the one
// CameraManager of the process is shared by every LibcameraCamera. The camera is chosen by id or
// index (select_camera), acquired, and configured for one stream of the best format
// (choose_libcamera_format) at the configured size; exposure (ExposureTime), gain (AnalogueGain)
// and the frame rate (FrameDurationLimits, free running only) are set when the camera has the
// controls (set_exposure() changes the first two on the next request queued). start() allocates the
// buffers (FrameBufferAllocator), maps their first planes and queues one request per buffer;
// completed requests come from libcamera's thread through the LibcameraStream; release() queues the
// request again. Camera::disconnected makes acquire() report device_lost; reopen() looks the camera
// up again. A camera libcamera does not list when this object is made is looked for again by
// start() and reopen(), which throw DeviceMissing until it is there. libcamera has no
// external-trigger control: in TriggerMode::external the sensor must be put into trigger mode by
// its driver (module parameter, device tree or sub-device control) and the frame rate is left to
// the trigger.
class LibcameraCamera final : public CameraSource {
 public:
  explicit LibcameraCamera(CameraConfig config);
  ~LibcameraCamera() override;
  LibcameraCamera(const LibcameraCamera&) = delete;
  LibcameraCamera& operator=(const LibcameraCamera&) = delete;

  const std::string& name() const override { return name_; }
  const CameraConfig& config() const override { return config_; }
  void start() override;
  void stop() override;
  bool streaming() const override;
  AcquireResult acquire(Nanoseconds timeout) override;
  void release(const Frame& frame) override;
  void reopen() override;
  // The controls of plan_libcamera_exposure(); while streaming they go with the next request
  // queued, else with Camera::start().
  void set_exposure(Nanoseconds exposure, double gain) override;
  // FrameDurationLimits' minimum, when the camera has the control.
  std::optional<Nanoseconds> shortest_frame_period() const override;

  const LibcameraFormat& negotiated_format() const;
  const std::string& camera_id() const;

 private:
  struct Impl;
  CameraConfig config_;
  std::string name_;
  std::unique_ptr<Impl> impl_;
};

// The libcamera version this binary was built with ("0.0.3"); empty when it was not.
std::string libcamera_build_version();

}  // namespace epipole::hal
