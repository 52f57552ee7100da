#pragma once

#include <cstddef>
#include <cstdint>

#include "epipole/core/image.hpp"
#include "epipole/core/simd.hpp"

namespace epipole::vision {

// A fixed-point remap (rectification) map: for every destination pixel (u, v), the source
// position (x + fx/32, y + fy/32) whose bilinear interpolation becomes the destination pixel.
// It holds the same information as OpenCV's CV_16SC2 + CV_16UC1 map pair (cv::convertMaps,
// cv::initUndistortRectifyMap(..., CV_16SC2, ...)), in the same layout, so a row of each can
// be copied into the other:
//
//   xy plane, int16, 2 * width elements per row: x0, y0, x1, y1, ... — the integer part
//     (floor) of the source coordinates; any value is allowed, including far outside.
//   fraction plane, uint16, width elements per row: fy * 32 + fx with fx, fy in [0, 31] — the
//     sub-pixel part in 1/32 pixel. Only the low 10 bits are used (OpenCV masks the same way).
//
// Rows of both planes are padded to 64 bytes (Image); a map of width x height takes
// height * (round_up(4 * width, 64) + round_up(2 * width, 64)) bytes.
class RemapMap {
 public:
  static constexpr int kFractionBits = 5;
  static constexpr int kFractionSteps = 1 << kFractionBits;                  // 32
  static constexpr int kFractionMask = kFractionSteps * kFractionSteps - 1;  // 1023
  static constexpr int kMaxSize = 32767;  // int16 coordinates: larger images cannot be addressed

  RemapMap() = default;
  // The identity map of a width x height image (every fraction 0).
  RemapMap(int width, int height);
  // A copy of existing planes: xy is 2 * width wide, fractions width wide, both of one height.
  RemapMap(ImageView<const std::int16_t> xy, ImageView<const std::uint16_t> fractions);

  // From floating-point maps (the source x and y of each destination pixel, as for
  // cv::remap with CV_32FC1 maps): each coordinate times 32 is rounded to the nearest integer
  // (ties to even, as cv::convertMaps' cvRound), saturated to int32 (NaN becomes INT32_MIN);
  // its low 5 bits are the fraction and the rest, saturated to int16, the integer part. For
  // finite coordinates inside int32 / 32 the result equals cv::convertMaps(..., CV_16SC2).
  static RemapMap from_float(ImageView<const float> map_x, ImageView<const float> map_y);
  // The same into an existing map of the size of map_x and map_y (no allocation).
  void assign_float(ImageView<const float> map_x, ImageView<const float> map_y);

  RemapMap(RemapMap&&) noexcept = default;
  RemapMap& operator=(RemapMap&&) noexcept = default;
  RemapMap clone() const;

  int width() const { return fractions_.width(); }
  int height() const { return fractions_.height(); }
  bool empty() const { return fractions_.empty(); }
  ImageView<std::int16_t> xy() { return xy_.view(); }
  ImageView<const std::int16_t> xy() const { return xy_.view(); }
  ImageView<std::uint16_t> fractions() { return fractions_.view(); }
  ImageView<const std::uint16_t> fractions() const { return fractions_.view(); }
  std::size_t size_bytes() const { return xy_.size_bytes() + fractions_.size_bytes(); }

 private:
  Image<std::int16_t> xy_;
  Image<std::uint16_t> fractions_;
};

struct RectifierConfig {
  int source_width = 0;  // size of the images given to rectify()
  int source_height = 0;
  int width = 0;  // size of the rectified image: the map's size
  int height = 0;
  std::uint8_t border = 0;  // value of every source pixel outside the image
  // False: the rectifier has no image of its own and rectifies only into the caller's (the
  // frame loop's pipeline keeps two per camera, one for the pair ahead).
  bool own_output = true;
};

// Bilinear remap of 8-bit gray images with a fixed map, the same result as
// cv::remap(src, dst, map1, map2, INTER_LINEAR, BORDER_CONSTANT, border) with the same maps
// (bit for bit on OpenCV 4.6): with the four neighbours S00 = src(x, y), S01 = src(x + 1, y),
// S10 = src(x, y + 1), S11 = src(x + 1, y + 1), each taking the border value when outside the
// source image,
//   dst = (S00 (32-fx)(32-fy) + S01 fx (32-fy) + S10 (32-fx) fy + S11 fx fy + 512) >> 10,
// which is OpenCV's weights in 1/32768 units (all exact multiples of 32) rounded with
// (sum + 2^14) >> 15. A destination pixel whose neighbours all lie outside is the border value.
// Coordinates may point anywhere: nothing outside the source image is ever read.
//
// Fixed memory: everything is allocated by the constructor; rectify() never allocates.
// Working set: the map, height * (round_up(4 * width, 64) + round_up(2 * width, 64)) bytes,
//              + the output image, height * round_up(width, 64) bytes
//              (about 7 * width * height bytes: 2.15 MB for 640x480).
// A stereo pair is two Rectifiers, one per camera.
class Rectifier {
 public:
  // Throws Error if a size is not in [1, 32767] or the map is not width x height.
  Rectifier(const RectifierConfig& config, RemapMap map, SimdPath path = best_simd_path());

  // Rectifies a source image into the rectifier's own image; the view stays valid until the
  // next call. Throws Error if the source size differs from the configuration, or the
  // rectifier has no image of its own.
  GrayView rectify(GrayView source);
  // Rectifies into a caller's image of the configured (destination) size, which must not
  // overlap the source. Throws Error on a size mismatch or overlap.
  void rectify(GrayView source, MutableGrayView destination) const;
  // Rectifies rows [first_row, end_row) of the rectifier's own image only (row bands of one
  // image on several threads at once: the bands must not overlap); returns the whole image.
  // Throws Error on a size mismatch, rows outside the image, or no image of its own.
  GrayView rectify_rows(GrayView source, int first_row, int end_row);
  // The same into a caller's image, as rectify(source, destination) checks it.
  void rectify_rows(GrayView source, MutableGrayView destination, int first_row, int end_row) const;

  std::size_t working_set_bytes() const;
  const RectifierConfig& config() const { return config_; }
  const RemapMap& map() const { return map_; }
  SimdPath simd_path() const { return path_; }
  // Exchanges the map for `other`, of the same size (Error otherwise), without allocating: a map
  // rebuilt beside the one in use takes its place between two images.
  void swap_map(RemapMap& other);

 private:
  // Throws Error for a source of another size than the configuration's.
  void check_source(GrayView source) const;
  void check_own_output() const;
  void remap_rows(GrayView source, MutableGrayView destination, int first_row, int end_row) const;

  RectifierConfig config_;
  SimdPath path_;
  RemapMap map_;
  GrayImage output_;
};

}  // namespace epipole::vision
