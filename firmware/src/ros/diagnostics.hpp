#pragma once

// Health as diagnostic_msgs/DiagnosticArray, as every output that speaks ROS 2 sends it: the
// status `epipole: health` (every field of the health message), and `epipole: calibration` (every
// field of the calibration's health: the rows' offset, the right camera's estimated turn and the
// corrections made) when the report has one. Fixed memory: nothing here allocates.
#include <array>
#include <cstddef>
#include <cstdint>
#include <string_view>
#include <vector>

#include "epipole/firmware/health_report.hpp"
#include "ros/ros_messages.hpp"

namespace epipole::firmware::ros {

// A message field as a diagnostic key and value: its name in the protocol, its value in decimal.
struct DiagnosticField {
  const char* key = "";
  std::array<char, 24> value{};
};
inline constexpr std::size_t kMaxDiagnosticFields = 64;

// diagnostic_msgs/DiagnosticStatus: OK 0, WARN 1.
inline constexpr std::uint8_t kDiagnosticOk = 0;
inline constexpr std::uint8_t kDiagnosticWarn = 1;

struct DiagnosticStatus {
  std::uint8_t level = kDiagnosticOk;
  const char* name = "";
  std::array<char, 160> message{};
  std::size_t field_count = 0;
  std::array<DiagnosticField, kMaxDiagnosticFields> fields;
};

// The calibration's status warns from rows half a pixel off: below that the disparity's block
// costs barely change; above it the rig needs correcting or calibrating again.
inline constexpr int kRowsOffWarningCentipx = 50;

// `epipole: health`: WARN when a flag is set or pairs were dropped since the health message
// before (whose `dropped` was `dropped_before`), else OK ("running").
void health_status(const protocol::Health& health, std::uint32_t dropped_before,
                   DiagnosticStatus& out);
// `epipole: calibration`: WARN when the rows are kRowsOffWarningCentipx or more off, else OK;
// the message says the offset, the estimated turn, and the corrections made or under way.
void calibration_status(const protocol::CalibrationHealth& calibration, DiagnosticStatus& out);

// Both statuses of a report into `out`; returns how many (1, or 2 with the calibration).
std::size_t diagnostic_statuses(const HealthReport& report, std::uint32_t dropped_before,
                                std::array<DiagnosticStatus, 2>& out);

// The DiagnosticArray in CDR (the recordings, the live view), the statuses from
// diagnostic_statuses().
void write_diagnostics(std::vector<std::uint8_t>& out, Time stamp, std::string_view hardware_id,
                       const HealthReport& report, std::uint32_t dropped_before,
                       std::array<DiagnosticStatus, 2>& scratch);

}  // namespace epipole::firmware::ros
