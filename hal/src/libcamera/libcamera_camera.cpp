// The libcamera camera backend. Built when pkg-config finds libcamera (Debian bookworm: 0.0.3).
// The only place that includes libcamera's headers and knows its version: the API differences
// between versions are handled here, with <libcamera/version.h>.
#include <sys/mman.h>

#include <libcamera/camera.h>
#include <libcamera/camera_manager.h>
#include <libcamera/control_ids.h>
#include <libcamera/controls.h>
#include <libcamera/formats.h>
#include <libcamera/framebuffer.h>
#include <libcamera/framebuffer_allocator.h>
#include <libcamera/request.h>
#include <libcamera/stream.h>
#include <libcamera/version.h>
#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <memory>
#include <mutex>
#include <string>
#include <string_view>
#include <vector>

#include "backends.hpp"
#include "epipole/core/error.hpp"
#include "epipole/hal/device_missing.hpp"
#include "epipole/hal/registry.hpp"
#include "libcamera/libcamera_camera.hpp"
#include "libcamera/libcamera_formats.hpp"

// ExposureTimeMode and AnalogueGainMode (manual or automatic) came with libcamera 0.5; before
// it, setting ExposureTime or AnalogueGain fixes the value by itself.
#define EPIPOLE_LIBCAMERA_AT_LEAST(major, minor) \
  (LIBCAMERA_VERSION_MAJOR > (major) ||          \
   (LIBCAMERA_VERSION_MAJOR == (major) && LIBCAMERA_VERSION_MINOR >= (minor)))
#if LIBCAMERA_VERSION_MAJOR == 0 && LIBCAMERA_VERSION_MINOR == 0 && LIBCAMERA_VERSION_PATCH < 3
#error "the libcamera backend needs libcamera 0.0.3 or newer"
#endif
#define EPIPOLE_LIBCAMERA_HAS_EXPOSURE_MODES EPIPOLE_LIBCAMERA_AT_LEAST(0, 5)

namespace epipole::hal {

namespace lc = libcamera;

namespace {

// The backend's table must hold libcamera's own codes (R16 is not in every version's list).
constexpr bool in_table(const char* name, const lc::PixelFormat& f) {
  for (const LibcameraFormat& e : kLibcameraFormats) {
    if (std::string_view(e.name) == name) {
      return e.fourcc == f.fourcc() && e.modifier == f.modifier();
    }
  }
  return false;
}
static_assert(in_table("R8", lc::formats::R8) && in_table("R10", lc::formats::R10) &&
              in_table("R10_CSI2P", lc::formats::R10_CSI2P) &&
              in_table("YUYV", lc::formats::YUYV) && in_table("NV12", lc::formats::NV12) &&
              in_table("YUV420", lc::formats::YUV420) && in_table("RGB888", lc::formats::RGB888) &&
              in_table("BGR888", lc::formats::BGR888));

// The process's one CameraManager (libcamera allows only one at a time), started on first use
// and stopped when the last camera lets it go.
class ManagerRef {
 public:
  ManagerRef() {
    const std::lock_guard<std::mutex> lock(mutex());
    if (users() == 0) {
      auto manager = std::make_unique<lc::CameraManager>();
      const int r = manager->start();
      if (r < 0) {
        throw Error(cat("libcamera: the camera manager does not start: ", std::strerror(-r)));
      }
      instance() = manager.release();
    }
    ++users();
  }
  ~ManagerRef() {
    const std::lock_guard<std::mutex> lock(mutex());
    if (--users() == 0) {
      instance()->stop();
      delete instance();
      instance() = nullptr;
    }
  }
  ManagerRef(const ManagerRef&) = delete;
  ManagerRef& operator=(const ManagerRef&) = delete;
  lc::CameraManager& operator*() const { return *instance(); }
  lc::CameraManager* operator->() const { return instance(); }

 private:
  static std::mutex& mutex() {
    static std::mutex m;
    return m;
  }
  static int& users() {
    static int n = 0;
    return n;
  }
  static lc::CameraManager*& instance() {
    static lc::CameraManager* p = nullptr;
    return p;
  }
};

std::vector<std::string> camera_ids(const lc::CameraManager& manager) {
  std::vector<std::string> ids;
  for (const std::shared_ptr<lc::Camera>& c : manager.cameras()) ids.push_back(c->id());
  return ids;
}

// A control's [min, max] when the camera states a usable range of type T.
template <typename T>
bool control_range(const lc::ControlInfo& info, lc::ControlType type, T& lo, T& hi) {
  const lc::ControlValue& mn = info.min();
  const lc::ControlValue& mx = info.max();
  if (mn.type() != type || mx.type() != type || mn.isArray() || mx.isArray()) return false;
  lo = mn.get<T>();
  hi = mx.get<T>();
  return hi >= lo && hi > T{0};
}

LibcameraControlRange range_of(const lc::ControlInfoMap& info, const lc::ControlId& id,
                               lc::ControlType type) {
  LibcameraControlRange r;
  const auto it = info.find(&id);
  if (it == info.end()) return r;
  r.present = true;
  if (type == lc::ControlTypeInteger32) {
    std::int32_t lo = 0, hi = 0;
    r.bounded = control_range(it->second, type, lo, hi);
    r.min = static_cast<double>(lo);
    r.max = static_cast<double>(hi);
  } else {
    float lo = 0.0f, hi = 0.0f;
    r.bounded = control_range(it->second, type, lo, hi);
    r.min = static_cast<double>(lo);
    r.max = static_cast<double>(hi);
  }
  return r;
}

LibcameraExposureLimits exposure_limits(const lc::ControlInfoMap& info) {
  LibcameraExposureLimits l;
  l.exposure_time = range_of(info, lc::controls::ExposureTime, lc::ControlTypeInteger32);
  l.analogue_gain = range_of(info, lc::controls::AnalogueGain, lc::ControlTypeFloat);
  l.ae_enable = info.find(&lc::controls::AeEnable) != info.end();
#if EPIPOLE_LIBCAMERA_HAS_EXPOSURE_MODES
  l.exposure_time_mode = info.find(&lc::controls::ExposureTimeMode) != info.end();
  l.analogue_gain_mode = info.find(&lc::controls::AnalogueGainMode) != info.end();
#endif
  return l;
}

void put(const LibcameraExposureControls& c, lc::ControlList& list) {
#if EPIPOLE_LIBCAMERA_HAS_EXPOSURE_MODES
  if (c.exposure_time_manual) {
    list.set(lc::controls::ExposureTimeMode, *c.exposure_time_manual
                                                 ? lc::controls::ExposureTimeModeManual
                                                 : lc::controls::ExposureTimeModeAuto);
  }
  if (c.analogue_gain_manual) {
    list.set(lc::controls::AnalogueGainMode, *c.analogue_gain_manual
                                                 ? lc::controls::AnalogueGainModeManual
                                                 : lc::controls::AnalogueGainModeAuto);
  }
#endif
  if (c.ae_enable) list.set(lc::controls::AeEnable, *c.ae_enable);
  if (c.exposure_time_us) list.set(lc::controls::ExposureTime, *c.exposure_time_us);
  if (c.analogue_gain) list.set(lc::controls::AnalogueGain, *c.analogue_gain);
}

}  // namespace

// ----------------------------------------------------------------------------------------------

struct LibcameraCamera::Impl final : LibcameraStream::Requeuer {
  explicit Impl(const CameraConfig& c) : config(c) {}
  ~Impl() { close(); }
  Impl(const Impl&) = delete;
  Impl& operator=(const Impl&) = delete;

  [[noreturn]] void fail(const std::string& what, int error) const {
    throw Error(
        cat("camera ", config.device, ": ", what, ": ", std::strerror(error < 0 ? -error : error)));
  }

  void open();
  void configure();
  void set_controls();
  void set_exposure(Nanoseconds exposure, double gain);
  void close();
  void start();
  void stop();
  bool requeue(int slot) override;
  void on_request_completed(lc::Request* request);
  void on_disconnected() { stream.ring().lose(); }

  const CameraConfig& config;
  ManagerRef manager;
  std::string id;  // resolved at the first open, so a reopen finds the same camera
  std::shared_ptr<lc::Camera> camera;
  bool acquired = false;
  std::unique_ptr<lc::CameraConfiguration> configuration;
  lc::Stream* lc_stream = nullptr;
  const LibcameraFormat* format = nullptr;
  std::size_t stride = 0;
  lc::ControlList controls{lc::controls::controls};  // sent with Camera::start()
  lc::ControlList pending{lc::controls::controls};   // sent with the next request queued
  bool has_pending = false;
  std::unique_ptr<lc::FrameBufferAllocator> allocator;
  std::vector<std::unique_ptr<lc::Request>> requests;
  struct Mapping {
    void* base = nullptr;
    std::size_t length = 0;
  };
  std::vector<Mapping> mappings;
  LibcameraStream stream;
  bool running = false;
};

void LibcameraCamera::Impl::open() {
  const std::vector<std::string> ids = camera_ids(*manager);
  if (id.empty()) id = ids[select_camera(config.device, ids)];
  camera = manager->get(id);
  if (!camera) {
    throw DeviceMissing(cat("camera ", config.device, ": libcamera camera ", id,
                            " is not present (cameras found: ", list_cameras(ids), ")"));
  }
  const int r = camera->acquire();
  if (r < 0) {
    camera.reset();
    fail(cat("cannot acquire libcamera camera ", id,
             r == -EBUSY ? " (busy: another process or camera object holds it)" : ""),
         r);
  }
  acquired = true;
  camera->requestCompleted.connect(this, &Impl::on_request_completed);
  camera->disconnected.connect(this, &Impl::on_disconnected);
  try {
    configure();
    set_controls();
  } catch (...) {
    close();
    throw;
  }
}

void LibcameraCamera::Impl::configure() {
  const bool mono = config.format == PixelFormat::grey || config.format == PixelFormat::y10 ||
                    config.format == PixelFormat::y16;
  // The stream role whose formats serve the request best comes first (a mono sensor's raw
  // stream, an ISP's viewfinder stream), the other one when it offers nothing we can use (vimc's
  // raw stream is Bayer only). A vector: 0.0.3 takes StreamRoles, 0.1 and later a Span of roles.
  const lc::StreamRole roles[2] = {mono ? lc::StreamRole::Raw : lc::StreamRole::Viewfinder,
                                   mono ? lc::StreamRole::Viewfinder : lc::StreamRole::Raw};
  std::string offered_names;
  format = nullptr;
  for (const lc::StreamRole role : roles) {
    configuration = camera->generateConfiguration(std::vector<lc::StreamRole>{role});
    if (!configuration || configuration->empty()) continue;
    const lc::StreamConfiguration& sc = configuration->at(0);
    std::vector<LibcameraFormatCode> offered;
    for (const lc::PixelFormat& f : sc.formats().pixelformats()) {
      offered.push_back({f.fourcc(), f.modifier()});
      offered_names += (offered_names.empty() ? "" : ", ") + f.toString();
    }
    if (offered.empty()) {  // a pipeline that lists no formats: its default one
      offered.push_back({sc.pixelFormat.fourcc(), sc.pixelFormat.modifier()});
      offered_names += (offered_names.empty() ? "" : ", ") + sc.pixelFormat.toString();
    }
    format = choose_libcamera_format(config.format, offered);
    if (format != nullptr) break;
  }
  if (format == nullptr) {
    throw Error(cat("camera ", config.device, ": pixel format ", to_string(config.format),
                    ": libcamera camera ", id,
                    " offers none of R8, NV12, YUV420, R16, R10, R10_CSI2P, YUYV, RGB888, "
                    "BGR888 (it offers: ",
                    offered_names.empty() ? "no stream" : offered_names, ")"));
  }
  lc::StreamConfiguration& sc = configuration->at(0);
  const lc::PixelFormat wanted(format->fourcc, format->modifier);
  sc.pixelFormat = wanted;
  sc.size = lc::Size(static_cast<unsigned>(config.width), static_cast<unsigned>(config.height));
  sc.bufferCount = static_cast<unsigned>(config.buffer_count);
  if (configuration->validate() == lc::CameraConfiguration::Invalid) {
    throw Error(cat("camera ", config.device, ": libcamera camera ", id, " rejects ", format->name,
                    " ", config.width, "x", config.height));
  }
  require(sc.size.width == static_cast<unsigned>(config.width) &&
              sc.size.height == static_cast<unsigned>(config.height),
          "camera ", config.device, ": size ", config.width, "x", config.height,
          " is not supported (libcamera offers ", sc.size.toString(), " in ", format->name, ")");
  require(sc.pixelFormat == wanted, "camera ", config.device, ": pixel format ", format->name,
          " was refused (libcamera chose ", sc.pixelFormat.toString(), ")");
  stride = sc.stride != 0 ? sc.stride : row_bytes(format->layout, config.width);
  const int r = camera->configure(configuration.get());
  if (r < 0) fail(cat("cannot configure ", format->name, " ", config.width, "x", config.height), r);
  lc_stream = sc.stream();
}

void LibcameraCamera::Impl::set_controls() {
  controls.clear();
  const lc::ControlInfoMap& info = camera->controls();
  const std::string& d = config.device;
  put(plan_libcamera_exposure(d, id, config.exposure, config.gain, exposure_limits(info),
                              EPIPOLE_LIBCAMERA_HAS_EXPOSURE_MODES, true),
      controls);
  // The trigger sets the rate in external mode; free running, the frame duration does.
  const auto limits = info.find(&lc::controls::FrameDurationLimits);
  if (config.trigger == TriggerMode::free_running && limits != info.end()) {
    const auto us = static_cast<std::int64_t>(std::llround(1e6 / config.fps));
    std::int64_t lo = 0, hi = 0;
    require(
        !control_range(limits->second, lc::ControlTypeInteger64, lo, hi) || (us >= lo && us <= hi),
        "camera ", d, ": frame rate ", config.fps, " is outside the camera's frame durations ", lo,
        "..", hi, " us");
    const std::int64_t duration[2] = {us, us};
    controls.set(lc::controls::FrameDurationLimits, lc::Span<const std::int64_t, 2>(duration));
  }
}

void LibcameraCamera::Impl::start() {
  if (running) return;
  require(camera != nullptr, "camera ", config.device, ": not open");
  try {
    allocator = std::make_unique<lc::FrameBufferAllocator>(camera);
    const int r = allocator->allocate(lc_stream);
    if (r < 0) fail("cannot allocate frame buffers", r);
    const std::vector<std::unique_ptr<lc::FrameBuffer>>& buffers = allocator->buffers(lc_stream);
    require(buffers.size() >= 2 && buffers.size() <= 64, "camera ", config.device,
            ": buffer count: libcamera gave ", buffers.size(), " buffers");
    std::vector<MappedPlane> planes;
    for (const std::unique_ptr<lc::FrameBuffer>& b : buffers) {
      require(!b->planes().empty(), "camera ", config.device, ": a frame buffer has no planes");
      const lc::FrameBuffer::Plane& p = b->planes()[0];
      // Map the dma-buf from its start: the plane's offset need not be page aligned.
      const std::size_t length = std::size_t{p.offset} + p.length;
      void* base = ::mmap(nullptr, length, PROT_READ, MAP_SHARED, p.fd.get(), 0);
      if (base == MAP_FAILED) fail("mmap of a frame buffer", errno);
      mappings.push_back({base, length});
      planes.push_back({static_cast<const std::uint8_t*>(base) + p.offset, p.length});
    }
    const std::uint32_t generation =
        stream.start(config.device, *format, config.width, config.height, stride, planes, *this);
    for (std::size_t i = 0; i < buffers.size(); ++i) {
      std::unique_ptr<lc::Request> request =
          camera->createRequest((std::uint64_t{generation} << 32) | i);
      require(request != nullptr, "camera ", config.device, ": cannot create a request");
      const int a = request->addBuffer(lc_stream, buffers[i].get());
      if (a < 0) fail("cannot add a buffer to a request", a);
      requests.push_back(std::move(request));
    }
    const int s = camera->start(&controls);
    if (s < 0) fail("cannot start libcamera camera " + id, s);
    running = true;
    for (const std::unique_ptr<lc::Request>& request : requests) {
      const int q = camera->queueRequest(request.get());
      if (q < 0) fail("cannot queue a request", q);
    }
  } catch (...) {
    stop();
    throw;
  }
}

void LibcameraCamera::Impl::stop() {
  if (running) {
    (void)camera->stop();  // cancels what is queued, synchronously
    running = false;
  }
  has_pending = false;  // the controls for start() hold the values
  stream.stop();
  requests.clear();
  for (const Mapping& m : mappings) ::munmap(m.base, m.length);
  mappings.clear();
  if (allocator) {
    (void)allocator->free(lc_stream);
    allocator.reset();
  }
}

void LibcameraCamera::Impl::close() {
  stop();
  if (camera) {
    camera->requestCompleted.disconnect(this);
    camera->disconnected.disconnect(this);
    if (acquired) (void)camera->release();
    acquired = false;
    configuration.reset();
    camera.reset();
  }
}

void LibcameraCamera::Impl::set_exposure(Nanoseconds exposure, double gain) {
  require(camera != nullptr, "camera ", config.device, ": exposure and gain: not open");
  const LibcameraExposureControls c = plan_libcamera_exposure(
      config.device, id, exposure, gain, exposure_limits(camera->controls()),
      EPIPOLE_LIBCAMERA_HAS_EXPOSURE_MODES, false);
  if (running) {
    pending.clear();
    put(c, pending);
    has_pending = true;
  }
}

bool LibcameraCamera::Impl::requeue(int slot) {
  lc::Request* request = requests[static_cast<std::size_t>(slot)].get();
  request->reuse(lc::Request::ReuseBuffers);
  if (has_pending) {  // set_exposure(): the controls go with this request
    request->controls().merge(pending);
    has_pending = false;
  }
  return camera->queueRequest(request) == 0;
}

// libcamera's thread: nothing here allocates; the completion goes through the ring.
void LibcameraCamera::Impl::on_request_completed(lc::Request* request) {
  RequestCompletion c;
  c.slot = static_cast<int>(request->cookie() & 0xffffffffu);
  c.generation = static_cast<std::uint32_t>(request->cookie() >> 32);
  c.cancelled = request->status() == lc::Request::RequestCancelled;
  if (const lc::FrameBuffer* buffer = request->findBuffer(lc_stream)) {
    const lc::FrameMetadata& m = buffer->metadata();
    c.cancelled = c.cancelled || m.status == lc::FrameMetadata::FrameCancelled;
    c.damaged = m.status == lc::FrameMetadata::FrameError;
    c.sequence = m.sequence;
    c.timestamp = static_cast<Nanoseconds>(m.timestamp);
    if (!m.planes().empty()) c.bytes_used = m.planes()[0].bytesused;
  } else {
    c.damaged = true;
  }
  if (const auto t = request->metadata().get(lc::controls::SensorTimestamp)) c.timestamp = *t;
  (void)stream.ring().complete(c);
}

// ----------------------------------------------------------------------------------------------

LibcameraCamera::LibcameraCamera(CameraConfig config) : config_(std::move(config)) {
  validate(config_);
  name_ = "libcamera:" + config_.device;
  impl_ = std::make_unique<Impl>(config_);
  try {
    impl_->open();
  } catch (const DeviceMissing&) {
    // Not listed yet: start() looks again, and RecoveringCamera waits for it.
  }
}

LibcameraCamera::~LibcameraCamera() = default;

void LibcameraCamera::start() {
  if (!impl_->camera) impl_->open();  // it was not there when the camera was made
  impl_->start();
}

void LibcameraCamera::stop() {
  impl_->stop();
}

bool LibcameraCamera::streaming() const {
  return impl_->running;
}

AcquireResult LibcameraCamera::acquire(Nanoseconds timeout) {
  return impl_->stream.acquire(timeout);
}

void LibcameraCamera::release(const Frame& frame) {
  impl_->stream.release(frame);
}

void LibcameraCamera::set_exposure(Nanoseconds exposure, double gain) {
  validate_exposure(config_.device, exposure, gain);
  impl_->set_exposure(exposure, gain);  // checks them against the camera first
  config_.exposure = exposure;
  config_.gain = gain;
  impl_->set_controls();  // what the next Camera::start() sends (the same checks passed)
}

void LibcameraCamera::reopen() {
  const bool was_running = impl_->running;
  impl_->close();
  impl_->open();
  if (was_running) impl_->start();
}

std::optional<Nanoseconds> LibcameraCamera::shortest_frame_period() const {
  if (impl_->camera == nullptr) return std::nullopt;
  const lc::ControlInfoMap& info = impl_->camera->controls();
  const auto limits = info.find(&lc::controls::FrameDurationLimits);
  std::int64_t lo = 0, hi = 0;
  if (limits == info.end() || !control_range(limits->second, lc::ControlTypeInteger64, lo, hi) ||
      lo <= 0) {
    return std::nullopt;
  }
  return static_cast<Nanoseconds>(lo) * 1000;  // microseconds
}

const LibcameraFormat& LibcameraCamera::negotiated_format() const {
  return *impl_->format;
}

const std::string& LibcameraCamera::camera_id() const {
  return impl_->id;
}

void register_libcamera(BackendRegistry& registry) {
  registry.add_camera("libcamera", [](const CameraConfig& config, const BackendContext&) {
    return std::unique_ptr<CameraSource>(std::make_unique<LibcameraCamera>(config));
  });
}

std::string libcamera_build_version() {
  return cat(LIBCAMERA_VERSION_MAJOR, ".", LIBCAMERA_VERSION_MINOR, ".", LIBCAMERA_VERSION_PATCH);
}

}  // namespace epipole::hal
