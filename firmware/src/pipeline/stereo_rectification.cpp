#include "epipole/firmware/stereo_rectification.hpp"

namespace epipole::firmware {

vision::RemapMap to_remap_map(const calib::FixedPointMap& map) {
  return vision::RemapMap(ImageView<const std::int16_t>(map.xy.view()),
                          ImageView<const std::uint16_t>(map.fractions.view()));
}

namespace {

vision::Rectifier make_rectifier(const calib::StereoCalibration& calibration, calib::Side side,
                                 SimdPath path, std::uint8_t border, bool own_output) {
  vision::RectifierConfig config;
  config.source_width = config.width = calibration.width;
  config.source_height = config.height = calibration.height;
  config.border = border;
  config.own_output = own_output;
  return vision::Rectifier(config, to_remap_map(calib::build_fixed_point_map(calibration, side)),
                           path);
}

}  // namespace

StereoRectifiers make_stereo_rectifiers(const calib::StereoCalibration& calibration, SimdPath path,
                                        std::uint8_t border, bool own_output) {
  return {make_rectifier(calibration, calib::Side::left, path, border, own_output),
          make_rectifier(calibration, calib::Side::right, path, border, own_output)};
}

}  // namespace epipole::firmware
