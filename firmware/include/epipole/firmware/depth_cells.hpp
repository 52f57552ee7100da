#pragma once

#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "epipole/calib/triangulation.hpp"
#include "epipole/core/image.hpp"

namespace epipole::firmware {

// The rectified left camera's pinhole (P1): focal lengths and principal point, pixels.
struct RectifiedPinhole {
  double fx = 0, cx = 0;
  double fy = 0, cy = 0;
};

// The pixels (u, v, d) a measure counts: those where u_factor u + v_factor v + d_factor d +
// constant >= 0 (d in pixels), e.g. those above the ground (calib::clearance_form).
struct PixelHalfSpace {
  double u_factor = 0, v_factor = 0, d_factor = 0, constant = 0;
};

struct DepthCellsConfig {
  int width = 0;  // the disparity image
  int height = 0;
  int max_disparity = 64;
  int columns = 1;  // cells across, splitting the band's horizontal field of view evenly by angle
  int rows = 1;     // and down, splitting its vertical field of view
  double band_top = 0;  // rows of the image measured, fractions of the height
  double band_bottom = 1;
  double min_depth_m = 0.2;   // nearer is reported as this
  double max_depth_m = 20.0;  // farther counts as nothing seen
  // A cell's nearest surface must cover at least this share of the cell's pixels (and at least
  // min_pixels), so that a few wrong disparities do not make phantom obstacles.
  double min_share = 0.002;
  int min_pixels = 12;
  // 1..255: only pixels whose disparity confidence (vision::StereoMatcher::confidence()) is at
  // least this count; 0: every valid pixel.
  int min_confidence = 0;
};

// The nearest depth in each cell of a grid over a band of the rectified left view, from a
// disparity image (x16, vision::kInvalidDisparity where unknown): per cell, the largest integer
// disparity that enough of the cell's pixels reach, refined to the mean disparity of the pixels of
// that integer bin and converted to depth (Z, metres) with Q. Cells go left to right, then top
// to bottom; columns split the band's horizontal field of view evenly by angle, rows its vertical
// one (pinhole). The obstacle sectors are one row of cells, the depth grid several.
//
// Fixed memory: the constructor allocates the column and row tables and a histogram of integer
// disparities per cell; measure() never allocates.
class DepthCells {
 public:
  // `what`: the board file's section, to name in errors. Throws Error for a bad configuration.
  DepthCells(const DepthCellsConfig& config, const calib::Triangulator& triangulator,
             RectifiedPinhole camera, std::string what);

  // Writes each cell's nearest depth in millimetres, or protocol::kUnknownDepth, to
  // `nearest_mm` (columns x rows of them). `confidence`: the disparity's, required with
  // config.min_confidence (ignored without). Throws Error on a size mismatch.
  // `counted`: only the pixels in this half-space count (null: all).
  void measure(ImageView<const std::int16_t> disparity, ImageView<const std::uint8_t> confidence,
               std::span<std::uint16_t> nearest_mm, const PixelHalfSpace* counted = nullptr);

  // The band's fields of view, degrees, and a column's centre from the optical axis (positive
  // to the right).
  double horizontal_fov_deg() const { return horizontal_.fov_deg; }
  double vertical_fov_deg() const { return vertical_.fov_deg; }
  double column_centre_deg(int column) const;
  const DepthCellsConfig& config() const { return config_; }
  std::size_t working_set_bytes() const;

 private:
  // Pixels to cells along one axis, evenly by angle.
  struct Axis {
    double first_edge_deg = 0;
    double fov_deg = 0;
    std::vector<std::uint8_t> cell_of;  // per pixel of the axis (rows: of the band)
  };
  static Axis split(int first, int end, int cells, double focal, double centre);

  DepthCellsConfig config_;
  const calib::Triangulator& triangulator_;
  std::string what_;
  int band_first_ = 0;
  int band_end_ = 0;
  Axis horizontal_, vertical_;
  std::vector<std::uint32_t> histogram_;  // cells x max_disparity: pixel counts
  std::vector<std::uint64_t> sums_;       // and the sums of their disparities x16 (a 1x1 grid of a
                                          // large image overflows 32 bits in one bin)
  std::vector<std::uint32_t> cell_pixels_;
  std::vector<std::uint32_t> column_pixels_;  // per column of cells: its pixels in one row
};

}  // namespace epipole::firmware
