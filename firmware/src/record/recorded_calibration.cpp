#include "record/recorded_calibration.hpp"

#include <string>

#include "epipole/core/mcap_reader.hpp"

namespace epipole::firmware::record {

std::optional<calib::StereoCalibration> recorded_calibration(const std::filesystem::path& file) {
  const std::optional<std::string> yaml = mcap::read_attachment(file, kCalibrationAttachment);
  if (!yaml) return std::nullopt;
  return calib::parse_calibration(*yaml,
                                  file.string() + ": " + std::string(kCalibrationAttachment));
}

}  // namespace epipole::firmware::record
