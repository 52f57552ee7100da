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

bool is_zero_copy(PixelFormat format) {
  return format == PixelFormat::grey || format == PixelFormat::nv12 || format == PixelFormat::yu12;
}

std::size_t bytes_per_pixel(PixelFormat format) {
  return format == PixelFormat::y10 || format == PixelFormat::y16 || format == PixelFormat::yuyv
             ? 2
             : 1;
}

std::size_t plane_bytes(PixelFormat format, int width, int height, std::size_t bytes_per_line) {
  return bytes_per_line * static_cast<std::size_t>(height - 1) +
         static_cast<std::size_t>(width) * bytes_per_pixel(format);
}

GrayView convert_plane(const std::uint8_t* data, std::size_t bytes, int width, int height,
                       std::size_t stride, std::size_t row_bytes, RowConversion convert,
                       MutableGrayView scratch) {
  require(width > 0 && height > 0 && data != nullptr, "camera buffer: empty");
  require(stride >= row_bytes, "camera buffer: ", stride, " bytes per line < the ", row_bytes,
          " of a ", width, "-pixel row");
  const std::size_t need = stride * static_cast<std::size_t>(height - 1) + row_bytes;
  require(bytes >= need, "camera buffer: ", bytes, " bytes, ", width, "x", height, " needs ", need);
  if (convert == nullptr) return {data, width, height, static_cast<std::ptrdiff_t>(stride)};
  require(scratch.width() == width && scratch.height() == height,
          "camera buffer: the conversion buffer is ", scratch.width(), "x", scratch.height(),
          ", not ", width, "x", height);
  for (int y = 0; y < height; ++y) {
    convert(data + static_cast<std::size_t>(y) * stride, scratch.row(y), width);
  }
  return scratch;
}

namespace {

void luma_of_yuyv(const std::uint8_t* in, std::uint8_t* out, int width) {
  for (int x = 0; x < width; ++x) out[x] = in[2 * x];
}

// Little-endian 16-bit samples with `bits` significant bits, to their 8 high bits.
template <int bits>
void high_bits_of_le16(const std::uint8_t* in, std::uint8_t* out, int width) {
  constexpr unsigned mask = (1u << bits) - 1;
  for (int x = 0; x < width; ++x) {
    const unsigned sample = (in[2 * x] | (unsigned{in[2 * x + 1]} << 8)) & mask;
    out[x] = static_cast<std::uint8_t>(sample >> (bits - 8));
  }
}

}  // namespace

GrayView gray_view(PixelFormat format, const std::uint8_t* data, std::size_t bytes, int width,
                   int height, std::size_t bytes_per_line, MutableGrayView scratch) {
  RowConversion convert = nullptr;
  if (format == PixelFormat::yuyv) convert = luma_of_yuyv;
  if (format == PixelFormat::y10) convert = high_bits_of_le16<10>;
  if (format == PixelFormat::y16) convert = high_bits_of_le16<16>;
  return convert_plane(data, bytes, width, height, bytes_per_line,
                       static_cast<std::size_t>(width) * bytes_per_pixel(format), convert, scratch);
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
  validate_exposure(d, config.exposure, config.gain);
  require(config.buffer_count >= 2 && config.buffer_count <= 32, "camera ", d, ": buffer count ",
          config.buffer_count, " is impossible (2..32)");
}

void validate_exposure(const std::string& device, Nanoseconds exposure, double gain) {
  require(exposure >= 0 && exposure <= kMaxExposure, "camera ", device, ": exposure ", exposure,
          " ns is impossible (0: automatic, at most ", kMaxExposure, " ns)");
  require(std::isfinite(gain) && gain >= 0.0 && gain <= kMaxGain, "camera ", device, ": gain ",
          gain, " is impossible (0: automatic, at most ", kMaxGain, ")");
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

TriggerConfig with_rate(const TriggerConfig& config, double rate_hz) {
  require(config.role == TriggerRole::master, "trigger ", config.line,
          ": a slave line cannot set a rate (", rate_hz,
          " Hz asked): the master that drives it sets the rate");
  TriggerConfig changed = config;
  changed.rate_hz = rate_hz;
  validate(changed);
  return changed;
}

Nanoseconds period_of(double rate_hz) {
  return static_cast<Nanoseconds>(1e9 / rate_hz + 0.5);
}

}  // namespace epipole::hal
