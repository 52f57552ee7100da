#pragma once

// The live view's colours of disparity: a rainbow from dark blue (far: small disparities) through
// green and yellow to dark red (near), as the host tool's pictures are coloured (a Turbo-like
// map, drawn here without OpenCV), and black where there is no disparity. The page draws its
// legend from the same table.
#include <array>
#include <cstdint>

#include "epipole/core/image.hpp"

namespace epipole::firmware::view {

using Rgb = std::array<std::uint8_t, 3>;

// 256 colours, from disparity 0 to the board's largest.
const std::array<Rgb, 256>& disparity_colours();

// The disparity (x16, negative where there is none) as RGB, 3 bytes a pixel, rows of `stride`
// bytes, for disparities 0..max_disparity.
void colour_disparity(ImageView<const std::int16_t> disparity16, int max_disparity,
                      std::uint8_t* rgb, std::size_t stride);

}  // namespace epipole::firmware::view
