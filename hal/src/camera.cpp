#include "epipole/hal/camera.hpp"

#include <cctype>
#include <cmath>

#include "epipole/core/error.hpp"
#include "epipole/hal/trigger.hpp"

namespace epipole::hal {

namespace {
constexpr PixelFormat kFormats[] = {PixelFormat::grey, PixelFormat::y10,  PixelFormat::y16,
                                    PixelFormat::yuyv, PixelFormat::nv12, PixelFormat::yu12};
}

const char* to_string(PixelFormat format) {
  switch (format) {
    case PixelFormat::grey:
      return "grey";
    case PixelFormat::y10:
      return "y10";
    case PixelFormat::y16:
      return "y16";
    case PixelFormat::yuyv:
      return "yuyv";
    case PixelFormat::nv12:
      return "nv12";
    case PixelFormat::yu12:
      return "yu12";
  }
  return "?";
}

std::optional<PixelFormat> parse_pixel_format(std::string_view name) {
  for (const PixelFormat f : kFormats) {
    const std::string_view candidate = to_string(f);
    if (candidate.size() != name.size()) continue;
    bool equal = true;
    for (std::size_t i = 0; i < name.size(); ++i) {
      if (std::tolower(static_cast<unsigned char>(name[i])) != candidate[i]) equal = false;
    }
    if (equal) return f;
  }
  return std::nullopt;
}

const char* to_string(AcquireStatus status) {
  switch (status) {
    case AcquireStatus::ok:
      return "ok";
    case AcquireStatus::timeout:
      return "timeout";
    case AcquireStatus::device_lost:
      return "device lost";
    case AcquireStatus::corrupt:
      return "corrupt frame";
  }
  return "?";
}

void validate(const CameraConfig& config) {
  const std::string& d = config.device;
  require(!d.empty(), "camera: no device given");
  require(config.width > 0 && config.height > 0 && config.width <= 16384 && config.height <= 16384,
          "camera ", d, ": size ", config.width, "x", config.height,
          " is impossible (1..16384 each)");
  const bool subsampled = config.format == PixelFormat::yuyv ||
                          config.format == PixelFormat::nv12 || config.format == PixelFormat::yu12;
  require(!subsampled || config.width % 2 == 0, "camera ", d, ": width ", config.width,
          " must be even for pixel format ", to_string(config.format));
  require((config.format != PixelFormat::nv12 && config.format != PixelFormat::yu12) ||
              config.height % 2 == 0,
          "camera ", d, ": height ", config.height, " must be even for pixel format ",
          to_string(config.format));
  require(std::isfinite(config.fps) && config.fps > 0.0 && config.fps <= 1000.0, "camera ", d,
          ": frame rate ", config.fps, " is impossible (0 < fps <= 1000)");
  require(config.exposure >= 0, "camera ", d, ": exposure ", config.exposure, " ns is negative");
  require(std::isfinite(config.gain) && config.gain >= 0.0, "camera ", d, ": gain ", config.gain,
          " is negative");
  require(config.buffer_count >= 2 && config.buffer_count <= 32, "camera ", d, ": buffer count ",
          config.buffer_count, " is impossible (2..32)");
}

void validate(const TriggerConfig& config) {
  require(!config.line.empty(), "trigger: no line given");
  require(std::isfinite(config.rate_hz) && config.rate_hz > 0.0 && config.rate_hz <= 1000.0,
          "trigger ", config.line, ": rate ", config.rate_hz,
          " Hz is impossible (0 < rate <= 1000)");
  const double period = 1e9 / config.rate_hz;
  require(config.pulse_width > 0 && static_cast<double>(config.pulse_width) < period, "trigger ",
          config.line, ": pulse width ", config.pulse_width, " ns does not fit the period ", period,
          " ns");
}

}  // namespace epipole::hal
