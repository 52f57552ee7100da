#include "ros/diagnostics.hpp"

#include <charconv>
#include <cstdarg>
#include <cstdio>
#include <cstdlib>
#include <cstring>

#include "epipole/core/cdr_writer.hpp"
#include "epipole/core/error.hpp"
#include "epipole/firmware/protocol/fields.hpp"

namespace epipole::firmware::ros {

namespace {

// Every field of a message as a key and its value, in the order visited.
struct FieldTexts {
  DiagnosticStatus& out;
  template <typename T>
  void operator()(const char* name, const T& value) {
    require(out.field_count < out.fields.size(), "a diagnostic status has more than ",
            out.fields.size(), " fields");
    DiagnosticField& f = out.fields[out.field_count++];
    f.key = name;
    const auto [end, ec] =
        std::to_chars(f.value.data(), f.value.data() + f.value.size() - 1, +value);
    *(ec == std::errc() ? end : f.value.data()) = '\0';
  }
  template <typename... A>
  void list(A&&...) {}  // health and the calibration's have no lists
};

template <typename Message>
void set_fields(const Message& message, DiagnosticStatus& out) {
  out.field_count = 0;
  FieldTexts texts{out};
  protocol::fields(texts, message);
}

// Appends to the status's message (cut at its size, never past it).
[[gnu::format(printf, 2, 3)]] void say(DiagnosticStatus& out, const char* format, ...) {
  const std::size_t used = std::strlen(out.message.data());
  if (used + 1 >= out.message.size()) return;
  std::va_list values;
  va_start(values, format);
  std::vsnprintf(out.message.data() + used, out.message.size() - used, format, values);
  va_end(values);
}

}  // namespace

void health_status(const protocol::Health& health, std::uint32_t dropped_before,
                   DiagnosticStatus& out) {
  out.name = "epipole: health";
  out.message[0] = '\0';
  if (health.flags != 0) {
    out.level = kDiagnosticWarn;
    say(out, "see flags");
  } else if (health.dropped != dropped_before) {  // counts wrap: not <
    out.level = kDiagnosticWarn;
    say(out, "pairs dropped");
  } else {
    out.level = kDiagnosticOk;
    say(out, "running");
  }
  set_fields(health, out);
}

void calibration_status(const protocol::CalibrationHealth& c, DiagnosticStatus& out) {
  out.name = "epipole: calibration";
  out.message[0] = '\0';
  out.level =
      std::abs(c.median_offset_centipx) >= kRowsOffWarningCentipx ? kDiagnosticWarn : kDiagnosticOk;
  say(out, "rows %+.2f px off", c.median_offset_centipx / 100.0);
  if ((c.flags & protocol::kDriftEstimated) != 0) {
    say(out, "; right camera turned %+.3f deg pitch, %+.3f deg roll over %u pairs",
        c.pitch_mdeg / 1000.0, c.roll_mdeg / 1000.0, static_cast<unsigned>(c.window_pairs));
  }
  if ((c.flags & protocol::kRigCorrecting) != 0) say(out, "; correcting");
  if (c.corrections > 0) {
    say(out, "; corrected %u times (%+.3f, %+.3f deg)", static_cast<unsigned>(c.corrections),
        c.corrected_pitch_mdeg / 1000.0, c.corrected_roll_mdeg / 1000.0);
  }
  set_fields(c, out);
}

std::size_t diagnostic_statuses(const HealthReport& report, std::uint32_t dropped_before,
                                std::array<DiagnosticStatus, 2>& out) {
  health_status(report.health, dropped_before, out[0]);
  if (!report.calibration) return 1;
  calibration_status(*report.calibration, out[1]);
  return 2;
}

void write_diagnostics(std::vector<std::uint8_t>& out, Time stamp, std::string_view hardware_id,
                       const HealthReport& report, std::uint32_t dropped_before,
                       std::array<DiagnosticStatus, 2>& scratch) {
  const std::size_t n = diagnostic_statuses(report, dropped_before, scratch);
  cdr::CdrWriter w(out);
  w.i32(stamp.sec);  // std_msgs/Header
  w.u32(stamp.nanosec);
  w.string("");
  w.u32(static_cast<std::uint32_t>(n));
  for (std::size_t s = 0; s < n; ++s) {
    const DiagnosticStatus& status = scratch[s];
    w.u8(status.level);
    w.string(status.name);
    w.string(status.message.data());
    w.string(hardware_id);
    w.u32(static_cast<std::uint32_t>(status.field_count));
    for (std::size_t i = 0; i < status.field_count; ++i) {
      w.string(status.fields[i].key);
      w.string(status.fields[i].value.data());
    }
  }
}

}  // namespace epipole::firmware::ros
