#include "v4l2/v4l2_camera.hpp"

#include <fcntl.h>
#include <linux/videodev2.h>
#include <poll.h>
#include <sys/ioctl.h>
#include <sys/mman.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstring>

#include "backends.hpp"
#include "device_node.hpp"
#include "epipole/core/error.hpp"
#include "epipole/hal/device_missing.hpp"
#include "epipole/hal/registry.hpp"

namespace epipole::hal {

namespace {

struct FormatCode {
  PixelFormat format;
  std::uint32_t fourcc;
};
constexpr FormatCode kCodes[] = {
    {PixelFormat::grey, V4L2_PIX_FMT_GREY}, {PixelFormat::y10, V4L2_PIX_FMT_Y10},
    {PixelFormat::y16, V4L2_PIX_FMT_Y16},   {PixelFormat::yuyv, V4L2_PIX_FMT_YUYV},
    {PixelFormat::nv12, V4L2_PIX_FMT_NV12}, {PixelFormat::yu12, V4L2_PIX_FMT_YUV420}};
// Zero-copy formats first, then those that need a conversion.
constexpr PixelFormat kPreference[] = {PixelFormat::grey, PixelFormat::nv12, PixelFormat::yu12,
                                       PixelFormat::y16,  PixelFormat::y10,  PixelFormat::yuyv};

int xioctl(int fd, unsigned long request, void* arg) {
  int r = 0;
  do {
    r = ::ioctl(fd, request, arg);
  } while (r < 0 && errno == EINTR);
  return r;
}

// The capture buffer type of the API the driver speaks.
std::uint32_t capture_type(bool multiplanar) {
  return multiplanar ? V4L2_BUF_TYPE_VIDEO_CAPTURE_MPLANE : V4L2_BUF_TYPE_VIDEO_CAPTURE;
}

// A memory-mapped capture buffer to query, queue or dequeue, with room for the planes of the
// multi-planar API (where the first plane holds the image); single-planar drivers fill `buf`.
class MappedBuffer {
 public:
  explicit MappedBuffer(bool multiplanar, std::uint32_t index = 0) : multiplanar_(multiplanar) {
    buf.type = capture_type(multiplanar);
    buf.memory = V4L2_MEMORY_MMAP;
    buf.index = index;
    if (multiplanar) {
      buf.m.planes = planes_;
      buf.length = VIDEO_MAX_PLANES;
    }
  }
  MappedBuffer(const MappedBuffer&) = delete;  // buf points into planes_
  MappedBuffer& operator=(const MappedBuffer&) = delete;

  std::size_t length() const { return multiplanar_ ? planes_[0].length : buf.length; }
  std::size_t bytes_used() const { return multiplanar_ ? planes_[0].bytesused : buf.bytesused; }
  off_t offset() const {
    return static_cast<off_t>(multiplanar_ ? planes_[0].m.mem_offset : buf.m.offset);
  }

  v4l2_buffer buf{};

 private:
  bool multiplanar_;
  v4l2_plane planes_[VIDEO_MAX_PLANES]{};
};

std::string fourcc_name(std::uint32_t fourcc) {
  std::string s(4, ' ');
  for (int i = 0; i < 4; ++i) {
    const auto c = static_cast<char>((fourcc >> (8 * i)) & 0xff);
    s[static_cast<std::size_t>(i)] = c >= 32 && c < 127 ? c : '?';
  }
  return s;
}

}  // namespace

std::uint32_t fourcc_of(PixelFormat format) {
  for (const FormatCode& c : kCodes) {
    if (c.format == format) return c.fourcc;
  }
  return 0;
}

std::optional<PixelFormat> pixel_format_of_fourcc(std::uint32_t fourcc) {
  for (const FormatCode& c : kCodes) {
    if (c.fourcc == fourcc) return c.format;
  }
  return std::nullopt;
}

std::optional<PixelFormat> choose_format(PixelFormat requested,
                                         std::span<const std::uint32_t> offered_fourccs) {
  auto offered = [&](PixelFormat f) {
    return std::find(offered_fourccs.begin(), offered_fourccs.end(), fourcc_of(f)) !=
           offered_fourccs.end();
  };
  if (offered(requested)) return requested;
  for (const PixelFormat f : kPreference) {
    if (offered(f)) return f;
  }
  return std::nullopt;
}

ClockId timestamp_clock(std::uint32_t buffer_flags) {
  return (buffer_flags & V4L2_BUF_FLAG_TIMESTAMP_MASK) == V4L2_BUF_FLAG_TIMESTAMP_MONOTONIC
             ? ClockId::monotonic
             : ClockId::other;
}

AcquireStatus buffer_status(std::uint32_t buffer_flags, std::size_t bytes_used, std::size_t length,
                            std::size_t needed) {
  const std::size_t bytes = std::min(bytes_used == 0 ? length : bytes_used, length);
  return (buffer_flags & V4L2_BUF_FLAG_ERROR) != 0 || bytes < needed ? AcquireStatus::corrupt
                                                                     : AcquireStatus::ok;
}

const char* v4l2_control_name(std::uint32_t id) {
  switch (id) {
    case V4L2_CID_EXPOSURE_AUTO:
      return "V4L2_CID_EXPOSURE_AUTO";
    case V4L2_CID_EXPOSURE_ABSOLUTE:
      return "V4L2_CID_EXPOSURE_ABSOLUTE";
    case V4L2_CID_AUTOGAIN:
      return "V4L2_CID_AUTOGAIN";
    case V4L2_CID_GAIN:
      return "V4L2_CID_GAIN";
    default:
      return "a control";
  }
}

V4l2ControlPlan plan_exposure_controls(const std::string& device, Nanoseconds exposure, double gain,
                                       const V4l2ExposureControls& controls, bool starting) {
  V4l2ControlPlan plan;
  const auto add = [&](std::uint32_t id, std::int32_t value) {
    plan.controls[static_cast<std::size_t>(plan.count++)] = {id, value};
  };
  const auto offers = [](const V4l2ControlInfo& c, int item) {
    return c.present && item >= 0 && item < 64 && (c.menu >> item & 1u) != 0;
  };
  const auto in_range = [](const V4l2ControlInfo& c, std::int64_t value) {
    return value >= c.minimum && value <= c.maximum;
  };
  const Nanoseconds exposure_us = exposure / 1000;
  if (exposure > 0) {
    require(controls.exposure_absolute.present, "camera ", device, ": exposure ", exposure_us,
            " us: the device has no V4L2_CID_EXPOSURE_ABSOLUTE control");
    const std::int64_t units = std::max<std::int64_t>((exposure + 50'000) / 100'000, 1);
    require(in_range(controls.exposure_absolute, units), "camera ", device, ": exposure ",
            exposure_us, " us is outside the device's ", controls.exposure_absolute.minimum, "..",
            controls.exposure_absolute.maximum, " x 100 us");
    if (controls.exposure_auto.present) {
      require(offers(controls.exposure_auto, V4L2_EXPOSURE_MANUAL), "camera ", device,
              ": exposure ", exposure_us,
              " us: the device's V4L2_CID_EXPOSURE_AUTO has no manual mode");
      add(V4L2_CID_EXPOSURE_AUTO, V4L2_EXPOSURE_MANUAL);
    }
    add(V4L2_CID_EXPOSURE_ABSOLUTE, static_cast<std::int32_t>(units));
  } else if (controls.exposure_auto.present) {
    const int mode = offers(controls.exposure_auto, V4L2_EXPOSURE_AUTO)
                         ? V4L2_EXPOSURE_AUTO
                         : V4L2_EXPOSURE_APERTURE_PRIORITY;
    require(offers(controls.exposure_auto, mode), "camera ", device,
            ": automatic exposure: the device's V4L2_CID_EXPOSURE_AUTO offers no automatic mode");
    add(V4L2_CID_EXPOSURE_AUTO, mode);
  } else {
    require(starting, "camera ", device,
            ": automatic exposure: the device has no V4L2_CID_EXPOSURE_AUTO control");
  }
  if (gain > 0.0) {
    require(controls.gain.present, "camera ", device, ": gain ", gain,
            ": the device has no V4L2_CID_GAIN control");
    const std::int64_t value = std::llround(gain);
    require(in_range(controls.gain, value), "camera ", device, ": gain ", gain,
            " is outside the device's ", controls.gain.minimum, "..", controls.gain.maximum,
            " (V4L2_CID_GAIN, in the driver's units)");
    if (controls.autogain.present) add(V4L2_CID_AUTOGAIN, 0);
    add(V4L2_CID_GAIN, static_cast<std::int32_t>(value));
  } else if (controls.autogain.present) {
    add(V4L2_CID_AUTOGAIN, 1);
  } else {
    require(starting, "camera ", device,
            ": automatic gain: the device has no V4L2_CID_AUTOGAIN control");
  }
  return plan;
}

// ----------------------------------------------------------------------------------------------

V4l2Camera::V4l2Camera(CameraConfig config) : config_(std::move(config)) {
  validate(config_);
  name_ = "v4l2:" + config_.device;
  try {
    open_and_negotiate();
  } catch (const DeviceMissing&) {
    // Not there yet: start() says so, and RecoveringCamera waits for it.
  }
}

void V4l2Camera::open_and_negotiate() {
  open_device();
  try {
    negotiate();
  } catch (...) {
    close_device();
    throw;
  }
}

V4l2Camera::~V4l2Camera() {
  close_device();
}

void V4l2Camera::fail(const char* what, int error) const {
  throw Error(cat("camera ", config_.device, ": ", what, ": ", std::strerror(error)));
}

void V4l2Camera::open_device() {
  fd_.reset(detail::open_device_node(config_.device, O_RDWR | O_NONBLOCK | O_CLOEXEC, "camera"));
  v4l2_capability cap{};
  if (xioctl(fd_.get(), VIDIOC_QUERYCAP, &cap) != 0) {
    const int error = errno;
    close_device();
    throw Error(cat("camera ", config_.device,
                    ": not a V4L2 device (VIDIOC_QUERYCAP: ", std::strerror(error), ")"));
  }
  const std::uint32_t caps =
      (cap.capabilities & V4L2_CAP_DEVICE_CAPS) != 0 ? cap.device_caps : cap.capabilities;
  if ((caps & V4L2_CAP_VIDEO_CAPTURE) != 0) {
    multiplanar_ = false;
  } else if ((caps & V4L2_CAP_VIDEO_CAPTURE_MPLANE) != 0) {
    multiplanar_ = true;
  } else {
    close_device();
    throw Error(cat("camera ", config_.device, ": not a video capture device"));
  }
  if ((caps & V4L2_CAP_STREAMING) == 0) {
    close_device();
    throw Error(cat("camera ", config_.device, ": does not support streaming I/O"));
  }
}

void V4l2Camera::negotiate() {
  const std::uint32_t type = capture_type(multiplanar_);
  std::vector<std::uint32_t> offered;
  for (std::uint32_t i = 0; i < 256; ++i) {
    v4l2_fmtdesc desc{};
    desc.index = i;
    desc.type = type;
    if (xioctl(fd_.get(), VIDIOC_ENUM_FMT, &desc) != 0) break;
    offered.push_back(desc.pixelformat);
  }
  const std::optional<PixelFormat> chosen = choose_format(config_.format, offered);
  if (!chosen) {
    std::string list;
    for (const std::uint32_t f : offered) list += (list.empty() ? "" : ", ") + fourcc_name(f);
    throw Error(cat("camera ", config_.device, ": pixel format ", to_string(config_.format),
                    ": the device offers none of grey, y10, y16, yuyv, nv12, yu12 (it offers: ",
                    list.empty() ? "nothing" : list, ")"));
  }
  format_ = *chosen;
  v4l2_format fmt{};
  fmt.type = type;
  const auto width = static_cast<std::uint32_t>(config_.width);
  const auto height = static_cast<std::uint32_t>(config_.height);
  if (multiplanar_) {
    fmt.fmt.pix_mp.width = width;
    fmt.fmt.pix_mp.height = height;
    fmt.fmt.pix_mp.pixelformat = fourcc_of(format_);
    fmt.fmt.pix_mp.field = V4L2_FIELD_NONE;
  } else {
    fmt.fmt.pix.width = width;
    fmt.fmt.pix.height = height;
    fmt.fmt.pix.pixelformat = fourcc_of(format_);
    fmt.fmt.pix.field = V4L2_FIELD_NONE;
  }
  if (xioctl(fd_.get(), VIDIOC_S_FMT, &fmt) != 0) fail("VIDIOC_S_FMT", errno);
  const std::uint32_t got_w = multiplanar_ ? fmt.fmt.pix_mp.width : fmt.fmt.pix.width;
  const std::uint32_t got_h = multiplanar_ ? fmt.fmt.pix_mp.height : fmt.fmt.pix.height;
  const std::uint32_t got_f = multiplanar_ ? fmt.fmt.pix_mp.pixelformat : fmt.fmt.pix.pixelformat;
  require(got_w == width && got_h == height, "camera ", config_.device, ": size ", config_.width,
          "x", config_.height, " is not supported (the driver offers ", got_w, "x", got_h, " in ",
          to_string(format_), ")");
  require(got_f == fourcc_of(format_), "camera ", config_.device, ": pixel format ",
          to_string(format_), " was refused (the driver chose ", fourcc_name(got_f), ")");
  bytes_per_line_ =
      multiplanar_ ? fmt.fmt.pix_mp.plane_fmt[0].bytesperline : fmt.fmt.pix.bytesperline;
  if (bytes_per_line_ == 0) bytes_per_line_ = width * bytes_per_pixel(format_);

  // The driver's frame intervals at this size and format: the shortest is the sensor's limit.
  shortest_period_.reset();
  v4l2_frmivalenum interval{};
  interval.pixel_format = fourcc_of(format_);
  interval.width = width;
  interval.height = height;
  for (; xioctl(fd_.get(), VIDIOC_ENUM_FRAMEINTERVALS, &interval) == 0; ++interval.index) {
    const v4l2_fract f =
        interval.type == V4L2_FRMIVAL_TYPE_DISCRETE ? interval.discrete : interval.stepwise.min;
    if (f.denominator == 0) break;
    const auto ns = static_cast<Nanoseconds>(1'000'000'000LL * f.numerator / f.denominator);
    if (!shortest_period_ || ns < *shortest_period_) shortest_period_ = ns;
    if (interval.type != V4L2_FRMIVAL_TYPE_DISCRETE) break;  // one range
  }

  v4l2_streamparm parm{};
  parm.type = type;
  parm.parm.capture.timeperframe.numerator = 1000;
  parm.parm.capture.timeperframe.denominator = static_cast<std::uint32_t>(config_.fps * 1000.0);
  (void)xioctl(fd_.get(), VIDIOC_S_PARM, &parm);  // not every driver has a frame-rate control

  apply_exposure(config_.exposure, config_.gain, true);
}

V4l2ControlInfo V4l2Camera::query_control(std::uint32_t id) const {
  v4l2_queryctrl q{};
  q.id = id;
  V4l2ControlInfo info;
  if (xioctl(fd_.get(), VIDIOC_QUERYCTRL, &q) != 0 || (q.flags & V4L2_CTRL_FLAG_DISABLED) != 0) {
    return info;
  }
  info.present = true;
  info.minimum = q.minimum;
  info.maximum = q.maximum;
  if (q.type == V4L2_CTRL_TYPE_MENU) {
    for (std::int32_t i = std::max(q.minimum, 0); i <= std::min(q.maximum, 63); ++i) {
      v4l2_querymenu m{};
      m.id = id;
      m.index = static_cast<std::uint32_t>(i);
      if (xioctl(fd_.get(), VIDIOC_QUERYMENU, &m) == 0) info.menu |= std::uint64_t{1} << i;
    }
  }
  return info;
}

void V4l2Camera::apply_exposure(Nanoseconds exposure, double gain, bool starting) {
  const V4l2ExposureControls available{
      query_control(V4L2_CID_EXPOSURE_AUTO), query_control(V4L2_CID_EXPOSURE_ABSOLUTE),
      query_control(V4L2_CID_AUTOGAIN), query_control(V4L2_CID_GAIN)};
  const V4l2ControlPlan plan =
      plan_exposure_controls(config_.device, exposure, gain, available, starting);
  for (int i = 0; i < plan.count; ++i) {
    v4l2_control c{plan.controls[static_cast<std::size_t>(i)].id,
                   plan.controls[static_cast<std::size_t>(i)].value};
    if (xioctl(fd_.get(), VIDIOC_S_CTRL, &c) != 0) {
      fail(cat("cannot set ", v4l2_control_name(c.id), " to ", c.value).c_str(), errno);
    }
  }
}

void V4l2Camera::set_exposure(Nanoseconds exposure, double gain) {
  validate_exposure(config_.device, exposure, gain);
  require(static_cast<bool>(fd_), "camera ", config_.device,
          ": exposure and gain: the device is not open");
  apply_exposure(exposure, gain, false);
  config_.exposure = exposure;
  config_.gain = gain;
}

void V4l2Camera::start() {
  if (streaming_) return;
  if (!fd_) open_and_negotiate();  // it was not there when the camera was made
  const std::uint32_t type = capture_type(multiplanar_);
  v4l2_requestbuffers req{};
  req.count = static_cast<std::uint32_t>(config_.buffer_count);
  req.type = type;
  req.memory = V4L2_MEMORY_MMAP;
  if (xioctl(fd_.get(), VIDIOC_REQBUFS, &req) != 0) fail("VIDIOC_REQBUFS (mmap)", errno);
  require(req.count >= 2, "camera ", config_.device, ": buffer count: the driver gave ", req.count,
          " buffers");
  buffers_.assign(req.count, Buffer{});
  for (std::uint32_t i = 0; i < req.count; ++i) {
    MappedBuffer b(multiplanar_, i);
    if (xioctl(fd_.get(), VIDIOC_QUERYBUF, &b.buf) != 0) fail("VIDIOC_QUERYBUF", errno);
    void* p =
        ::mmap(nullptr, b.length(), PROT_READ | PROT_WRITE, MAP_SHARED, fd_.get(), b.offset());
    if (p == MAP_FAILED) fail("mmap", errno);
    buffers_[i] = {p, b.length()};
    if (xioctl(fd_.get(), VIDIOC_QBUF, &b.buf) != 0) fail("VIDIOC_QBUF", errno);
  }
  scratch_.clear();
  if (!is_zero_copy(format_)) {
    for (std::uint32_t i = 0; i < req.count; ++i)
      scratch_.emplace_back(config_.width, config_.height);
  }
  int t = static_cast<int>(type);
  if (xioctl(fd_.get(), VIDIOC_STREAMON, &t) != 0) fail("VIDIOC_STREAMON", errno);
  streaming_ = true;
}

void V4l2Camera::stop() {
  if (fd_ && streaming_) {
    int t = static_cast<int>(capture_type(multiplanar_));
    (void)xioctl(fd_.get(), VIDIOC_STREAMOFF, &t);
  }
  for (const Buffer& b : buffers_) {
    if (b.data != nullptr) ::munmap(b.data, b.length);
  }
  buffers_.clear();
  if (fd_ && streaming_) {
    v4l2_requestbuffers req{};
    req.type = capture_type(multiplanar_);
    req.memory = V4L2_MEMORY_MMAP;
    (void)xioctl(fd_.get(), VIDIOC_REQBUFS, &req);
  }
  streaming_ = false;
  ++generation_;
}

void V4l2Camera::close_device() {
  stop();
  fd_.reset();
}

void V4l2Camera::reopen() {
  const bool was_streaming = streaming_;
  close_device();
  open_and_negotiate();
  if (was_streaming) start();
}

AcquireResult V4l2Camera::acquire(Nanoseconds timeout) {
  if (!fd_ || !streaming_) return {AcquireStatus::device_lost, {}};
  pollfd p{fd_.get(), POLLIN, 0};
  const int ms =
      timeout <= 0
          ? 0
          : static_cast<int>(std::min<Nanoseconds>((timeout + 999'999) / 1'000'000, 1'000'000'000));
  int ready = 0;
  do {
    ready = ::poll(&p, 1, ms);
  } while (ready < 0 && errno == EINTR);
  if (ready == 0) return {AcquireStatus::timeout, {}};
  if (ready < 0 || (p.revents & (POLLERR | POLLHUP | POLLNVAL)) != 0) {
    return {AcquireStatus::device_lost, {}};
  }
  MappedBuffer dequeued(multiplanar_);
  v4l2_buffer& buf = dequeued.buf;
  if (xioctl(fd_.get(), VIDIOC_DQBUF, &buf) != 0) {
    return {errno == EAGAIN ? AcquireStatus::timeout : AcquireStatus::device_lost, {}};
  }
  const std::size_t used = dequeued.bytes_used();
  const Buffer& mapped = buffers_[buf.index];
  const std::size_t bytes = std::min(used == 0 ? mapped.length : used, mapped.length);
  const std::size_t need = plane_bytes(format_, config_.width, config_.height, bytes_per_line_);
  const Nanoseconds timestamp = static_cast<Nanoseconds>(buf.timestamp.tv_sec) * 1'000'000'000 +
                                static_cast<Nanoseconds>(buf.timestamp.tv_usec) * 1'000;
  if (buffer_status(buf.flags, used, mapped.length, need) == AcquireStatus::corrupt) {
    (void)xioctl(fd_.get(), VIDIOC_QBUF, &buf);  // a damaged frame: give it back at once
    return corrupt_frame(buf.sequence, timestamp, timestamp_clock(buf.flags));
  }
  MutableGrayView scratch;
  if (!scratch_.empty()) scratch = scratch_[buf.index].view();
  Frame frame;
  frame.gray = gray_view(format_, static_cast<const std::uint8_t*>(mapped.data), bytes,
                         config_.width, config_.height, bytes_per_line_, scratch);
  frame.sequence = buf.sequence;
  frame.timestamp = timestamp;
  frame.clock = timestamp_clock(buf.flags);
  frame.buffer = static_cast<int>(buf.index);
  frame.generation = generation_;
  return {AcquireStatus::ok, frame};
}

void V4l2Camera::release(const Frame& frame) {
  if (!frame.valid() || frame.generation != generation_ || !fd_) return;
  MappedBuffer b(multiplanar_, static_cast<std::uint32_t>(frame.buffer));
  (void)xioctl(fd_.get(), VIDIOC_QBUF, &b.buf);
}

std::size_t V4l2Camera::working_set_bytes() const {
  std::size_t n = 0;
  for (const GrayImage& image : scratch_) n += image.size_bytes();
  return n;
}

void register_v4l2(BackendRegistry& registry) {
  registry.add_camera("v4l2",
                      [](const CameraConfig& config, const BackendContext&) {
                        return std::unique_ptr<CameraSource>(std::make_unique<V4l2Camera>(config));
                      },
                      {.needs_device = true});
}

}  // namespace epipole::hal
