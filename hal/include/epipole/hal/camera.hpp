#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>

#include "epipole/core/image.hpp"
#include "epipole/hal/clock.hpp"

namespace epipole::hal {

// Pixel formats a camera backend may be asked for. Every backend delivers an 8-bit gray view.
enum class PixelFormat { grey, y10, y16, yuyv, nv12, yu12 };

const char* to_string(PixelFormat format);
// "grey", "y10", "y16", "yuyv", "nv12", "yu12" (case-insensitive); nullopt for anything else.
std::optional<PixelFormat> parse_pixel_format(std::string_view name);

// --- The gray plane of a captured buffer, for every backend ---

// Whether the gray plane is the buffer itself (grey, nv12, yu12: the luma plane comes first).
bool is_zero_copy(PixelFormat format);
// Bytes per pixel of a row of the first plane: 2 for y10, y16 and yuyv, else 1.
std::size_t bytes_per_pixel(PixelFormat format);
// The bytes one plane of the geometry needs: bytes_per_line * (height - 1) + one row.
std::size_t plane_bytes(PixelFormat format, int width, int height, std::size_t bytes_per_line);
// The gray view of one captured plane: for zero-copy formats a view into `data` itself; y10
// and y16 (little-endian 16-bit samples, 10 or 16 significant bits) are scaled to 8 bits and
// yuyv's luma is taken, into `scratch` (width x height, sized once at start). Throws Error when
// `bytes` is too small for the geometry (a truncated buffer).
GrayView gray_view(PixelFormat format, const std::uint8_t* data, std::size_t bytes, int width,
                   int height, std::size_t bytes_per_line, MutableGrayView scratch);
// What every gray view shares: checks that `bytes` hold `height` rows of `row_bytes` bytes,
// `stride` apart, then views `data` in place (convert == nullptr) or converts each row into
// `scratch` (width x height). Throws Error for a truncated buffer or a wrong scratch size.
using RowConversion = void (*)(const std::uint8_t* in, std::uint8_t* out, int width);
GrayView convert_plane(const std::uint8_t* data, std::size_t bytes, int width, int height,
                       std::size_t stride, std::size_t row_bytes, RowConversion convert,
                       MutableGrayView scratch);

enum class TriggerMode { free_running, external };

struct CameraConfig {
  std::string device;  // /dev/video0, a libcamera id, or "left"/"right" on the simulated board
  int width = 640;
  int height = 480;
  PixelFormat format = PixelFormat::grey;
  double fps = 30.0;         // free-running rate
  Nanoseconds exposure = 0;  // 0: automatic; at most kMaxExposure
  // The sensor's gain as a multiplier (1.0: unity, 2.0: +6 dB), as libcamera's AnalogueGain;
  // 0: automatic; at most kMaxGain. V4L2 defines no unit for its gain control: the v4l2 backend
  // sends the value rounded, in the driver's own units (docs/hal.md).
  double gain = 0.0;
  TriggerMode trigger = TriggerMode::free_running;
  int buffer_count = 4;  // the fixed ring of frame buffers
};

inline constexpr Nanoseconds kMaxExposure = 10'000'000'000;  // 10 s
inline constexpr double kMaxGain = 1000.0;

// Throws Error naming the device and the setting when a configuration cannot be valid.
void validate(const CameraConfig& config);
// The part of validate() that set_exposure() checks: 0 <= exposure <= kMaxExposure,
// 0 <= gain <= kMaxGain (finite). Throws Error naming the device and the value.
void validate_exposure(const std::string& device, Nanoseconds exposure, double gain);

// A frame lent by a camera: a zero-copy gray view into one of its buffers, valid until it is
// released (or the camera is stopped or reopened).
struct Frame {
  GrayView gray;
  std::uint32_t sequence = 0;  // the trigger sequence (free running: the frame counter)
  Nanoseconds timestamp = 0;
  ClockId clock = ClockId::monotonic;
  int buffer = -1;               // the camera's buffer index; -1: no frame
  std::uint32_t generation = 0;  // the camera's stream generation (bumped by reopen)
  bool valid() const { return buffer >= 0; }
};

enum class AcquireStatus {
  ok,           // a frame
  timeout,      // no frame before the timeout
  device_lost,  // the device is gone (or stalled past recovery): reopen()
  corrupt,      // a frame came but the driver flagged it damaged or it was short: its buffer
                // went straight back (the result's frame has its sequence and time, no
                // buffer); the device still streams
};

struct AcquireResult {
  AcquireStatus status = AcquireStatus::timeout;
  Frame frame;
};

const char* to_string(AcquireStatus status);

// A damaged frame's result: its number and time, so that its trigger is accounted for.
inline AcquireResult corrupt_frame(std::uint32_t sequence, Nanoseconds timestamp, ClockId clock) {
  AcquireResult r;
  r.status = AcquireStatus::corrupt;
  r.frame.sequence = sequence;
  r.frame.timestamp = timestamp;
  r.frame.clock = clock;
  return r;
}

// A camera. acquire() and release() never allocate and never throw once the camera streams;
// configuration and opening errors throw Error naming the device and the setting.
class CameraSource {
 public:
  virtual ~CameraSource() = default;
  virtual const std::string& name() const = 0;
  virtual const CameraConfig& config() const = 0;
  virtual void start() = 0;
  virtual void stop() = 0;
  virtual bool streaming() const = 0;
  virtual AcquireResult acquire(Nanoseconds timeout) = 0;
  // Gives a frame's buffer back. Frames of an earlier generation (before a reopen) are ignored.
  virtual void release(const Frame& frame) = 0;
  // Closes and opens the device again and restarts streaming if it was streaming; throws Error
  // naming the device when it cannot be opened. The exposure and gain of config() are applied
  // again.
  virtual void reopen() = 0;
  // Changes exposure and gain, streaming or not (0: automatic, as in CameraConfig); config()
  // holds the new values. Throws Error naming the device and the setting when the camera cannot
  // take them (a control it lacks, a value outside the range it states); config() then keeps the
  // old ones. Called from the thread that calls acquire(); the backend's own code does not
  // allocate (libcamera may, when it queues the request that carries the controls).
  virtual void set_exposure(Nanoseconds exposure, double gain) = 0;
  // How long after its trigger edge a frame is stamped, when the backend knows it (the
  // simulated cameras); on hardware the board file says (pairing.edge_delay_us).
  virtual std::optional<Nanoseconds> edge_delay() const { return std::nullopt; }
  // The shortest frame period the sensor can follow at the configured size and format (its
  // highest frame rate), when the backend can tell (V4L2's frame intervals, libcamera's
  // FrameDurationLimits, the simulated sensor's readout); a trigger faster than it is refused.
  virtual std::optional<Nanoseconds> shortest_frame_period() const { return std::nullopt; }
  // The frame buffers it keeps on the heap (a driver's mmap'ed buffers are the kernel's).
  virtual std::size_t working_set_bytes() const { return 0; }
};

}  // namespace epipole::hal
