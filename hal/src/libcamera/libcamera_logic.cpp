// The parts of the libcamera backend that need no libcamera: formats, gray views, camera
// selection, the request ring and the acquire/release logic. Built everywhere, so their tests
// run in every build (cross builds included).
#include <algorithm>
#include <cctype>
#include <chrono>

#include "epipole/core/error.hpp"
#include "epipole/hal/clock.hpp"
#include "epipole/hal/device_missing.hpp"
#include "libcamera/libcamera_camera.hpp"
#include "libcamera/libcamera_formats.hpp"

namespace epipole::hal {

namespace {

using L = LibcameraLayout;
constexpr auto& kFormats = kLibcameraFormats;

bool offered(const LibcameraFormat& f, std::span<const LibcameraFormatCode> codes) {
  return std::any_of(codes.begin(), codes.end(), [&](const LibcameraFormatCode& c) {
    return c.fourcc == f.fourcc && c.modifier == f.modifier;
  });
}

}  // namespace

std::span<const LibcameraFormat> libcamera_formats() {
  return kFormats;
}

const LibcameraFormat* find_libcamera_format(LibcameraFormatCode code) {
  for (const LibcameraFormat& f : kFormats) {
    if (f.fourcc == code.fourcc && f.modifier == code.modifier) return &f;
  }
  return nullptr;
}

const LibcameraFormat* choose_libcamera_format(PixelFormat requested,
                                               std::span<const LibcameraFormatCode> offered_codes) {
  for (const LibcameraFormat& f : kFormats) {
    if (f.requestable && f.format == requested && offered(f, offered_codes)) return &f;
  }
  for (const LibcameraFormat& f : kFormats) {
    if (offered(f, offered_codes)) return &f;
  }
  return nullptr;
}

bool is_zero_copy(LibcameraLayout layout) {
  return layout == L::r8 || layout == L::nv12 || layout == L::yuv420;
}

std::size_t row_bytes(LibcameraLayout layout, int width) {
  const auto w = static_cast<std::size_t>(width);
  switch (layout) {
    case L::r8:
    case L::nv12:
    case L::yuv420:
      return w;
    case L::r10:
    case L::r16:
    case L::yuyv:
      return 2 * w;
    case L::r10_csi2p:
      return (w + 3) / 4 * 5;
    case L::rgb888:
    case L::bgr888:
      return 3 * w;
  }
  return w;
}

namespace {

// MIPI CSI-2 packed 10 bits: bytes 0..3 of each 5-byte group are the 8 high bits of 4 pixels.
void high_bits_of_csi2p10(const std::uint8_t* in, std::uint8_t* out, int width) {
  for (int x = 0; x < width; ++x) out[x] = in[x / 4 * 5 + x % 4];
}

// BT.601 luma in 8-bit fixed point, (77 R + 150 G + 29 B + 128) / 256, of 24-bit pixels whose
// red byte is at `r` (0 or 2) and blue byte at 2 - r.
template <int r>
void luma_of_rgb(const std::uint8_t* in, std::uint8_t* out, int width) {
  for (int x = 0; x < width; ++x) {
    const std::uint8_t* p = in + 3 * x;
    out[x] = static_cast<std::uint8_t>((77 * p[r] + 150 * p[1] + 29 * p[2 - r] + 128) >> 8);
  }
}

}  // namespace

GrayView gray_view(LibcameraLayout layout, const std::uint8_t* data, std::size_t bytes, int width,
                   int height, std::size_t stride, MutableGrayView scratch) {
  PixelFormat same = PixelFormat::grey;  // the layouts the V4L2 conversions know
  switch (layout) {
    case L::r8:
    case L::nv12:
    case L::yuv420:
      break;
    case L::r10:
      same = PixelFormat::y10;
      break;
    case L::r16:
      same = PixelFormat::y16;
      break;
    case L::yuyv:
      same = PixelFormat::yuyv;
      break;
    case L::r10_csi2p:
      return convert_plane(data, bytes, width, height, stride, row_bytes(layout, width),
                           high_bits_of_csi2p10, scratch);
    case L::rgb888:  // bytes B, G, R
      return convert_plane(data, bytes, width, height, stride, row_bytes(layout, width),
                           luma_of_rgb<2>, scratch);
    case L::bgr888:  // bytes R, G, B
      return convert_plane(data, bytes, width, height, stride, row_bytes(layout, width),
                           luma_of_rgb<0>, scratch);
  }
  return gray_view(same, data, bytes, width, height, stride, scratch);
}

std::string list_cameras(std::span<const std::string> ids) {
  if (ids.empty()) return "none";
  std::string list;
  for (std::size_t i = 0; i < ids.size(); ++i) {
    if (i > 0) list += ", ";
    list += cat(i, ": ", ids[i]);
  }
  return list;
}

std::size_t select_camera(std::string_view device, std::span<const std::string> ids) {
  for (std::size_t i = 0; i < ids.size(); ++i) {
    if (ids[i] == device) return i;
  }
  const bool number = !device.empty() && device.size() <= 6 &&
                      std::all_of(device.begin(), device.end(), [](char c) {
                        return std::isdigit(static_cast<unsigned char>(c)) != 0;
                      });
  if (number) {
    std::size_t index = 0;
    for (const char c : device) index = index * 10 + static_cast<std::size_t>(c - '0');
    if (index < ids.size()) return index;
  }
  throw DeviceMissing(cat("camera ", device, ": no libcamera camera with that ",
                          number ? "index" : "id", " (cameras found: ", list_cameras(ids), ")"));
}

LibcameraExposureControls plan_libcamera_exposure(const std::string& device,
                                                  const std::string& camera_id,
                                                  Nanoseconds exposure, double gain,
                                                  const LibcameraExposureLimits& limits, bool modes,
                                                  bool starting) {
  LibcameraExposureControls c;
  const auto fits = [](const LibcameraControlRange& r, double v) {
    return !r.bounded || (v >= r.min && v <= r.max);
  };
  if (exposure > 0) {
    require(limits.exposure_time.present, "camera ", device, ": exposure ", exposure,
            " ns: libcamera camera ", camera_id, " has no ExposureTime control");
    const auto us = static_cast<std::int32_t>(std::max<Nanoseconds>(exposure / 1000, 1));
    require(fits(limits.exposure_time, us), "camera ", device, ": exposure ", exposure,
            " ns is outside the camera's ", limits.exposure_time.min, "..",
            limits.exposure_time.max, " us");
    c.exposure_time_us = us;
  }
  if (gain > 0.0) {
    require(limits.analogue_gain.present, "camera ", device, ": gain ", gain, ": libcamera camera ",
            camera_id, " has no AnalogueGain control");
    require(fits(limits.analogue_gain, gain), "camera ", device, ": gain ", gain,
            " is outside the camera's analogue gain ", limits.analogue_gain.min, "..",
            limits.analogue_gain.max);
    c.analogue_gain = static_cast<float>(gain);
  }
  const auto automatic = [&](bool has_control, const char* what, const char* control) {
    require(has_control || starting, "camera ", device, ": automatic ", what, ": libcamera camera ",
            camera_id, " has no ", control, " control");
    return has_control;
  };
  if (modes) {
    if (exposure > 0 && limits.exposure_time_mode) c.exposure_time_manual = true;
    if (exposure == 0 && automatic(limits.exposure_time_mode, "exposure", "ExposureTimeMode")) {
      c.exposure_time_manual = false;
    }
    if (gain > 0.0 && limits.analogue_gain_mode) c.analogue_gain_manual = true;
    if (gain == 0.0 && automatic(limits.analogue_gain_mode, "gain", "AnalogueGainMode")) {
      c.analogue_gain_manual = false;
    }
  } else if (exposure > 0 && gain > 0.0) {
    if (limits.ae_enable) c.ae_enable = false;
  } else if (automatic(limits.ae_enable, exposure == 0 ? "exposure" : "gain", "AeEnable")) {
    c.ae_enable = true;
  }
  return c;
}

// ----------------------------------------------------------------------------------------------

std::uint32_t RequestRing::start(int slots) {
  require(slots > 0, "request ring: ", slots, " slots");
  const std::lock_guard<std::mutex> lock(mutex_);
  const auto n = static_cast<std::size_t>(slots);
  states_.assign(n, State::queued);
  completions_.assign(n, RequestCompletion{});
  order_.assign(n, -1);
  head_ = 0;
  size_ = 0;
  running_ = true;
  lost_ = false;
  return ++generation_;
}

void RequestRing::stop() {
  {
    const std::lock_guard<std::mutex> lock(mutex_);
    std::fill(states_.begin(), states_.end(), State::idle);
    size_ = 0;
    running_ = false;
    ++generation_;
  }
  changed_.notify_all();
}

bool RequestRing::complete(const RequestCompletion& completion) {
  {
    const std::lock_guard<std::mutex> lock(mutex_);
    const int slot = completion.slot;
    if (!running_ || completion.generation != generation_ || slot < 0 ||
        static_cast<std::size_t>(slot) >= states_.size() ||
        states_[static_cast<std::size_t>(slot)] != State::queued) {
      return false;
    }
    const auto s = static_cast<std::size_t>(slot);
    states_[s] = State::ready;
    completions_[s] = completion;
    order_[(head_ + size_) % order_.size()] = slot;
    ++size_;
  }
  changed_.notify_one();
  return true;
}

void RequestRing::lose() {
  {
    const std::lock_guard<std::mutex> lock(mutex_);
    lost_ = true;
  }
  changed_.notify_all();
}

RequestRing::Wait RequestRing::wait(Nanoseconds timeout, RequestCompletion& completion) {
  std::unique_lock<std::mutex> lock(mutex_);
  const auto until = std::chrono::steady_clock::now() +
                     std::chrono::nanoseconds(std::max<Nanoseconds>(timeout, 0));
  changed_.wait_until(lock, until, [&] { return size_ > 0 || lost_ || !running_; });
  if (size_ == 0) return lost_ || !running_ ? Wait::lost : Wait::timeout;
  const int slot = order_[head_];
  head_ = (head_ + 1) % order_.size();
  --size_;
  states_[static_cast<std::size_t>(slot)] = State::lent;
  completion = completions_[static_cast<std::size_t>(slot)];
  return Wait::ok;
}

bool RequestRing::give_back(int slot, std::uint32_t generation) {
  const std::lock_guard<std::mutex> lock(mutex_);
  if (generation != generation_ || slot < 0 || static_cast<std::size_t>(slot) >= states_.size() ||
      states_[static_cast<std::size_t>(slot)] != State::lent) {
    return false;
  }
  states_[static_cast<std::size_t>(slot)] = State::queued;
  return true;
}

std::uint32_t RequestRing::generation() const {
  const std::lock_guard<std::mutex> lock(mutex_);
  return generation_;
}

int RequestRing::slots() const {
  const std::lock_guard<std::mutex> lock(mutex_);
  return static_cast<int>(states_.size());
}

int RequestRing::count(State state) const {
  const std::lock_guard<std::mutex> lock(mutex_);
  return static_cast<int>(std::count(states_.begin(), states_.end(), state));
}

int RequestRing::queued() const {
  return count(State::queued);
}
int RequestRing::ready() const {
  return count(State::ready);
}
int RequestRing::lent() const {
  return count(State::lent);
}

// ----------------------------------------------------------------------------------------------

std::uint32_t LibcameraStream::start(const std::string& device, const LibcameraFormat& format,
                                     int width, int height, std::size_t stride,
                                     std::span<const MappedPlane> planes, Requeuer& requeuer) {
  require(!planes.empty(), "camera ", device, ": no frame buffers");
  const std::size_t row = row_bytes(format.layout, width);
  require(stride >= row, "camera ", device, ": stride ", stride, " is below the ", row,
          " bytes of a ", width, "-pixel ", format.name, " row");
  const std::size_t needed = stride * static_cast<std::size_t>(height - 1) + row;
  for (std::size_t i = 0; i < planes.size(); ++i) {
    require(planes[i].data != nullptr && planes[i].length >= needed, "camera ", device,
            ": frame buffer ", i, " holds ", planes[i].length, " bytes, ", format.name, " ", width,
            "x", height, " needs ", needed);
  }
  stop();
  layout_ = format.layout;
  width_ = width;
  height_ = height;
  stride_ = stride;
  needed_ = needed;
  planes_.assign(planes.begin(), planes.end());
  scratch_.clear();
  if (!is_zero_copy(layout_)) {
    scratch_.reserve(planes.size());
    for (std::size_t i = 0; i < planes.size(); ++i) scratch_.emplace_back(width, height);
  }
  requeuer_ = &requeuer;
  return ring_.start(static_cast<int>(planes.size()));
}

void LibcameraStream::stop() {
  ring_.stop();
  requeuer_ = nullptr;
}

void LibcameraStream::requeue(int slot, std::uint32_t generation) {
  if (requeuer_ == nullptr || !ring_.give_back(slot, generation)) return;
  if (!requeuer_->requeue(slot)) ring_.lose();
}

AcquireResult LibcameraStream::acquire(Nanoseconds timeout) {
  if (requeuer_ == nullptr) return {AcquireStatus::device_lost, {}};
  const MonotonicClock clock;
  const Nanoseconds deadline = clock.now() + std::max<Nanoseconds>(timeout, 0);
  while (true) {
    RequestCompletion c;
    const RequestRing::Wait w = ring_.wait(deadline - clock.now(), c);
    if (w == RequestRing::Wait::timeout) return {AcquireStatus::timeout, {}};
    if (w == RequestRing::Wait::lost) return {AcquireStatus::device_lost, {}};
    if (c.cancelled) {  // not a frame: queue it again and wait on
      requeue(c.slot, c.generation);
      continue;
    }
    const auto slot = static_cast<std::size_t>(c.slot);
    const MappedPlane& plane = planes_[slot];
    const std::size_t bytes =
        std::min(c.bytes_used == 0 ? plane.length : c.bytes_used, plane.length);
    if (c.damaged || bytes < needed_) {
      requeue(c.slot, c.generation);
      return corrupt_frame(c.sequence, c.timestamp, ClockId::monotonic);
    }
    MutableGrayView scratch;
    if (!scratch_.empty()) scratch = scratch_[slot].view();
    Frame frame;
    frame.gray = gray_view(layout_, plane.data, bytes, width_, height_, stride_, scratch);
    frame.sequence = c.sequence;
    frame.timestamp = c.timestamp;
    frame.clock = ClockId::monotonic;
    frame.buffer = c.slot;
    frame.generation = c.generation;
    return {AcquireStatus::ok, frame};
  }
}

void LibcameraStream::release(const Frame& frame) {
  if (!frame.valid()) return;
  requeue(frame.buffer, frame.generation);
}

}  // namespace epipole::hal
