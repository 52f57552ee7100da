#include "epipole/firmware/depth_cells.hpp"

#include <algorithm>
#include <cmath>

#include "epipole/core/angles.hpp"
#include "epipole/core/error.hpp"
#include "epipole/firmware/protocol/messages.hpp"
#include "epipole/vision/stereo.hpp"

namespace epipole::firmware {

DepthCells::Axis DepthCells::split(int first, int end, int cells, double focal, double centre) {
  const auto angle = [&](double u) { return degrees(std::atan((u - centre) / focal)); };
  Axis a;
  a.first_edge_deg = angle(first - 0.5);
  a.fov_deg = angle(end - 0.5) - a.first_edge_deg;
  a.cell_of.resize(static_cast<std::size_t>(end - first));
  for (int u = first; u < end; ++u) {
    const int c = static_cast<int>((angle(u) - a.first_edge_deg) / a.fov_deg * cells);
    a.cell_of[static_cast<std::size_t>(u - first)] =
        static_cast<std::uint8_t>(std::clamp(c, 0, cells - 1));
  }
  return a;
}

DepthCells::DepthCells(const DepthCellsConfig& config, const calib::Triangulator& triangulator,
                       RectifiedPinhole camera, std::string what)
    : config_(config), triangulator_(triangulator), what_(std::move(what)) {
  require(config.width > 0 && config.height > 0, what_, ": image size ", config.width, "x",
          config.height, " is empty");
  require(config.columns >= 1 && config.columns <= 255 && config.rows >= 1 && config.rows <= 255,
          what_, ": ", config.columns, "x", config.rows, " cells is outside 1..255 each way");
  require(config.max_disparity >= 1, what_, ": the disparity range is empty");
  require(config.band_top >= 0 && config.band_top < config.band_bottom && config.band_bottom <= 1,
          what_, ": band ", config.band_top, "..", config.band_bottom, " is not within 0..1");
  require(config.min_depth_m >= 0 && config.max_depth_m > config.min_depth_m &&
              config.max_depth_m < 65.535,
          what_, ": depth range ", config.min_depth_m, "..", config.max_depth_m,
          " m is not within 0..65.535 m");
  require(config.min_confidence >= 0 && config.min_confidence <= 255, what_, ": confidence ",
          config.min_confidence, " is outside 0..255");
  const auto valid = [](double focal, double centre) {
    return std::isfinite(focal) && focal > 0 && std::isfinite(centre);
  };
  require(valid(camera.fx, camera.cx), what_, ": the rectified camera (fx ", camera.fx, ", cx ",
          camera.cx, ") is not valid");
  band_first_ = static_cast<int>(config.band_top * config.height);
  band_end_ =
      std::min(config.height,
               std::max(band_first_ + 1, static_cast<int>(config.band_bottom * config.height)));
  horizontal_ = split(0, config.width, config.columns, camera.fx, camera.cx);
  if (valid(camera.fy, camera.cy)) {
    vertical_ = split(band_first_, band_end_, config.rows, camera.fy, camera.cy);
  } else {
    // One row of cells needs no vertical angles (the obstacle sectors are given fx and cx only).
    require(config.rows == 1, what_, ": the rectified camera (fy ", camera.fy, ", cy ", camera.cy,
            ") is not valid");
    vertical_.cell_of.assign(static_cast<std::size_t>(band_end_ - band_first_), 0);
  }
  const auto cells = static_cast<std::size_t>(config.columns * config.rows);
  histogram_.assign(cells * static_cast<std::size_t>(config.max_disparity), 0);
  sums_.assign(histogram_.size(), 0);
  cell_pixels_.assign(cells, 0);
  column_pixels_.assign(static_cast<std::size_t>(config.columns), 0);
  for (const std::uint8_t c : horizontal_.cell_of) ++column_pixels_[c];
}

double DepthCells::column_centre_deg(int column) const {
  return horizontal_.first_edge_deg + (column + 0.5) * horizontal_.fov_deg / config_.columns;
}

std::size_t DepthCells::working_set_bytes() const {
  return horizontal_.cell_of.size() + vertical_.cell_of.size() + histogram_.size() * 4 +
         sums_.size() * sizeof(std::uint64_t) + cell_pixels_.size() * 4 + column_pixels_.size() * 4;
}

void DepthCells::measure(ImageView<const std::int16_t> disparity,
                         ImageView<const std::uint8_t> confidence,
                         std::span<std::uint16_t> nearest_mm, const PixelHalfSpace* counted) {
  require(disparity.width() == config_.width && disparity.height() == config_.height, what_,
          ": disparity image ", disparity.width(), "x", disparity.height(),
          " is not the configured ", config_.width, "x", config_.height);
  const bool trusted_only = config_.min_confidence > 0;
  require(!trusted_only || same_size(confidence, disparity), what_, ": a confidence of ",
          confidence.width(), "x", confidence.height(), " for a ", config_.width, "x",
          config_.height, " disparity (min_confidence needs the matcher's)");
  const std::size_t cells = cell_pixels_.size();
  require(nearest_mm.size() >= cells, what_, ": room for ", nearest_mm.size(), " of ", cells,
          " cells");
  const int D = config_.max_disparity;
  std::fill(histogram_.begin(), histogram_.end(), 0u);
  std::fill(sums_.begin(), sums_.end(), std::uint64_t{0});
  std::fill(cell_pixels_.begin(), cell_pixels_.end(), 0u);
  // In locals: the counts' stores may alias the members, and the compiler would load them
  // again for every pixel.
  const int width = config_.width;
  const int min_confidence = config_.min_confidence;
  const std::uint8_t* const column_of = horizontal_.cell_of.data();
  std::uint32_t* const histogram = histogram_.data();
  std::uint64_t* const sums = sums_.data();
  // A pixel counts when 1 <= v < D * kDisparityScale (a disparity whose integer part is below
  // D): v - 1 is one of the `counted_values` below that.
  const auto counted_values = static_cast<unsigned>(D * vision::kDisparityScale - 1);
  for (int y = band_first_; y < band_end_; ++y) {
    const std::int16_t* row = disparity.row(y);
    const std::uint8_t* trust = trusted_only ? confidence.row(y) : nullptr;
    const int first_cell =
        vertical_.cell_of[static_cast<std::size_t>(y - band_first_)] * config_.columns;
    for (int k = 0; k < config_.columns; ++k) {
      cell_pixels_[static_cast<std::size_t>(first_cell + k)] +=
          column_pixels_[static_cast<std::size_t>(k)];
    }
    // The half-space's test, per pixel: u_factor x + d_factor v / 16 + this >= 0.
    const float row_term =
        counted != nullptr ? static_cast<float>(counted->v_factor * y + counted->constant) : 0.0f;
    const float u_factor = counted != nullptr ? static_cast<float>(counted->u_factor) : 0.0f;
    const float d_factor =
        counted != nullptr ? static_cast<float>(counted->d_factor / vision::kDisparityScale) : 0.0f;
    for (int x = 0; x < width; ++x) {
      const int v = row[x];
      if (static_cast<unsigned>(v - 1) >= counted_values) continue;
      if (trust != nullptr && trust[x] < min_confidence) continue;
      if (counted != nullptr &&
          u_factor * static_cast<float>(x) + d_factor * static_cast<float>(v) + row_term < 0.0f) {
        continue;
      }
      const unsigned d = static_cast<unsigned>(v) / vision::kDisparityScale;  // v > 0
      const std::size_t bin = static_cast<std::size_t>(first_cell + column_of[x]) * D + d;
      ++histogram[bin];
      sums[bin] += static_cast<std::uint64_t>(v);
    }
  }
  for (std::size_t c = 0; c < cells; ++c) {
    const std::uint32_t* h = &histogram_[c * static_cast<std::size_t>(D)];
    const std::uint64_t* sum = &sums_[c * static_cast<std::size_t>(D)];
    const double needed = std::max<double>(config_.min_pixels, config_.min_share * cell_pixels_[c]);
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
    nearest_mm[c] = mm;
  }
}

}  // namespace epipole::firmware
