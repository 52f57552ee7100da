#pragma once

#include <cstdint>
#include <filesystem>

#include "epipole/core/image.hpp"

namespace epipole {

// Image files for the host side (simulated cameras, the host tool, tests). The format is read
// from the file's first bytes, not its name. Every failure throws Error naming the file.
//
// load_gray decodes to 8-bit gray the way OpenCV's imread(IMREAD_GRAYSCALE) does, so results
// can be compared pixel for pixel: JPEG through libjpeg's own gray output, PNG through libpng
// (16-bit samples keep their high byte; colour converted with weights 0.299/0.587/0.114),
// binary PGM (P5, 8 or 16 bit). An image of more than kMaxImagePixels, or a PGM whose data the
// file does not hold, is an Error before anything is allocated for it.
inline constexpr long long kMaxImagePixels = 64ll * 1024 * 1024;
GrayImage load_gray(const std::filesystem::path& file);

// 16-bit gray (e.g. a disparity PNG holding disparity*16, or KITTI's ground truth); an 8-bit
// file's samples keep their values, 0..255 (Middlebury's ground truth: disparities in pixels).
Image<std::uint16_t> load_gray16(const std::filesystem::path& file);

// Writes PNG when the name ends in .png, binary PGM/PPM when it ends in .pgm/.ppm.
void save_image(const std::filesystem::path& file, ImageView<const std::uint8_t> image);
void save_image(const std::filesystem::path& file, ImageView<const std::uint16_t> image);
void save_image(const std::filesystem::path& file, ImageView<const Rgb8> image);

}  // namespace epipole
