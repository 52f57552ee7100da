#include "epipole/firmware/obstacles.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "epipole/core/error.hpp"
#include "epipole/vision/stereo.hpp"

namespace epipole::firmware {

namespace {
double degrees(double radians) {
  return radians * 180.0 / std::numbers::pi;
}
}  // namespace

ObstacleSectors::ObstacleSectors(const ObstacleConfig& config,
                                 const calib::Triangulator& triangulator, double fx, double cx)
    : config_(config), triangulator_(triangulator) {
  require(config.width > 0 && config.height > 0, "obstacles: image size ", config.width, "x",
          config.height, " is empty");
  require(config.sectors >= 1 && config.sectors <= protocol::kMaxSectors,
          "obstacles: ", config.sectors, " sectors is outside 1..", protocol::kMaxSectors);
  require(config.max_disparity >= 1, "obstacles: the disparity range is empty");
  require(config.band_top >= 0 && config.band_top < config.band_bottom && config.band_bottom <= 1,
          "obstacles: band ", config.band_top, "..", config.band_bottom, " is not within 0..1");
  require(config.min_depth_m >= 0 && config.max_depth_m > config.min_depth_m &&
              config.max_depth_m < 65.535,
          "obstacles: depth range ", config.min_depth_m, "..", config.max_depth_m,
          " m is not within 0..65.535 m");
  require(config.min_confidence >= 0 && config.min_confidence <= 255, "obstacles: confidence ",
          config.min_confidence, " is outside 0..255");
  require(std::isfinite(fx) && fx > 0 && std::isfinite(cx), "obstacles: the rectified camera (fx ",
          fx, ", cx ", cx, ") is not valid");
  const auto angle = [&](double u) { return degrees(std::atan((u - cx) / fx)); };
  first_edge_deg_ = angle(-0.5);
  fov_deg_ = angle(config.width - 0.5) - first_edge_deg_;
  sector_of_column_.resize(static_cast<std::size_t>(config.width));
  for (int u = 0; u < config.width; ++u) {
    const int s = static_cast<int>((angle(u) - first_edge_deg_) / fov_deg_ * config.sectors);
    sector_of_column_[static_cast<std::size_t>(u)] =
        static_cast<std::uint8_t>(std::clamp(s, 0, config.sectors - 1));
  }
  histogram_.assign(static_cast<std::size_t>(config.sectors * config.max_disparity), 0);
  sums_.assign(histogram_.size(), 0);
  band_pixels_.assign(static_cast<std::size_t>(config.sectors), 0);
}

double ObstacleSectors::sector_centre_deg(int sector) const {
  return first_edge_deg_ + (sector + 0.5) * fov_deg_ / config_.sectors;
}

std::size_t ObstacleSectors::working_set_bytes() const {
  return sector_of_column_.size() + histogram_.size() * 4 + sums_.size() * 4 +
         band_pixels_.size() * 4;
}

const protocol::Obstacles& ObstacleSectors::measure(ImageView<const std::int16_t> disparity,
                                                    std::uint32_t frame,
                                                    ImageView<const std::uint8_t> confidence) {
  require(disparity.width() == config_.width && disparity.height() == config_.height,
          "obstacles: disparity image ", disparity.width(), "x", disparity.height(),
          " is not the configured ", config_.width, "x", config_.height);
  const bool trusted_only = config_.min_confidence > 0;
  require(!trusted_only || same_size(confidence, disparity), "obstacles: a confidence of ",
          confidence.width(), "x", confidence.height(), " for a ", config_.width, "x",
          config_.height, " disparity (min_confidence needs the matcher's)");
  const int D = config_.max_disparity;
  std::fill(histogram_.begin(), histogram_.end(), 0u);
  std::fill(sums_.begin(), sums_.end(), 0u);
  std::fill(band_pixels_.begin(), band_pixels_.end(), 0u);
  const int y0 = static_cast<int>(config_.band_top * config_.height);
  const int y1 = std::max(y0 + 1, static_cast<int>(config_.band_bottom * config_.height));
  for (int y = y0; y < std::min(y1, config_.height); ++y) {
    const std::int16_t* row = disparity.row(y);
    const std::uint8_t* trust = trusted_only ? confidence.row(y) : nullptr;
    for (int x = 0; x < config_.width; ++x) {
      const int s = sector_of_column_[static_cast<std::size_t>(x)];
      ++band_pixels_[static_cast<std::size_t>(s)];
      const int d = row[x] / vision::kDisparityScale;
      if (row[x] <= 0 || d >= D) continue;
      if (trust != nullptr && trust[x] < config_.min_confidence) continue;
      const auto bin = static_cast<std::size_t>(s * D + d);
      ++histogram_[bin];
      sums_[bin] += static_cast<std::uint32_t>(row[x]);
    }
  }
  result_.frame = frame;
  result_.count = static_cast<std::uint8_t>(config_.sectors);
  result_.field_of_view_centideg = static_cast<std::uint16_t>(std::lround(fov_deg_ * 100));
  for (int s = 0; s < config_.sectors; ++s) {
    const std::uint32_t* h = &histogram_[static_cast<std::size_t>(s * D)];
    const std::uint32_t* sum = &sums_[static_cast<std::size_t>(s * D)];
    const double needed = std::max<double>(
        config_.min_pixels, config_.min_share * band_pixels_[static_cast<std::size_t>(s)]);
    std::uint32_t reached = 0;
    int nearest = 0;  // integer disparity; 0: nothing
    for (int d = D - 1; d >= 1; --d) {
      reached += h[d];
      if (reached >= needed) {
        nearest = d;
        break;
      }
    }
    std::uint16_t mm = protocol::kUnknownDepth;
    if (nearest > 0) {
      // The mean disparity of the pixels in that bin (d .. d + 1).
      const double d = static_cast<double>(sum[nearest]) / h[nearest] / vision::kDisparityScale;
      const double z = triangulator_.depth(d);
      if (std::isfinite(z) && z > 0 && z <= config_.max_depth_m) {
        mm = static_cast<std::uint16_t>(std::lround(std::max(z, config_.min_depth_m) * 1000));
      }
    }
    result_.nearest_mm[static_cast<std::size_t>(s)] = mm;
  }
  return result_;
}

}  // namespace epipole::firmware
