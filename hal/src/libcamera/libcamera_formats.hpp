#pragma once

// The libcamera backend's formats as DRM fourccs and modifiers (what libcamera::PixelFormat
// holds), without libcamera's headers: libcamera_logic.cpp uses the table everywhere,
// libcamera_camera.cpp checks it against libcamera's own formats.h at compile time.
#include <cstdint>

#include "libcamera/libcamera_camera.hpp"

namespace epipole::hal {

constexpr std::uint32_t drm_fourcc(char a, char b, char c, char d) {
  return static_cast<std::uint32_t>(static_cast<unsigned char>(a)) |
         static_cast<std::uint32_t>(static_cast<unsigned char>(b)) << 8 |
         static_cast<std::uint32_t>(static_cast<unsigned char>(c)) << 16 |
         static_cast<std::uint32_t>(static_cast<unsigned char>(d)) << 24;
}
// libcamera's MIPI CSI-2 packing modifier (vendor 11, modifier 1).
inline constexpr std::uint64_t kCsi2Packed = (std::uint64_t{11} << 56) | 1;

// In order of preference: zero-copy first, then the conversions.
inline constexpr LibcameraFormat kLibcameraFormats[] = {
    {LibcameraLayout::r8, "R8", drm_fourcc('R', '8', ' ', ' '), 0, true, PixelFormat::grey},
    {LibcameraLayout::nv12, "NV12", drm_fourcc('N', 'V', '1', '2'), 0, true, PixelFormat::nv12},
    {LibcameraLayout::yuv420, "YUV420", drm_fourcc('Y', 'U', '1', '2'), 0, true, PixelFormat::yu12},
    {LibcameraLayout::r16, "R16", drm_fourcc('R', '1', '6', ' '), 0, true, PixelFormat::y16},
    {LibcameraLayout::r10, "R10", drm_fourcc('R', '1', '0', ' '), 0, true, PixelFormat::y10},
    {LibcameraLayout::r10_csi2p, "R10_CSI2P", drm_fourcc('R', '1', '0', ' '), kCsi2Packed, true,
     PixelFormat::y10},
    {LibcameraLayout::yuyv, "YUYV", drm_fourcc('Y', 'U', 'Y', 'V'), 0, true, PixelFormat::yuyv},
    {LibcameraLayout::rgb888, "RGB888", drm_fourcc('R', 'G', '2', '4'), 0, false,
     PixelFormat::grey},
    {LibcameraLayout::bgr888, "BGR888", drm_fourcc('B', 'G', '2', '4'), 0, false,
     PixelFormat::grey},
};

}  // namespace epipole::hal
