#include "view/disparity_colours.hpp"

#include <algorithm>
#include <cmath>

namespace epipole::firmware::view {

namespace {

// The colours the map passes through, at even steps from 0 to 1.
constexpr Rgb kAnchors[] = {{48, 18, 59},   {70, 107, 227}, {40, 188, 235}, {50, 241, 152},
                            {164, 252, 60}, {250, 186, 57}, {230, 80, 20},  {122, 4, 3}};

std::array<Rgb, 256> make_colours() {
  std::array<Rgb, 256> table{};
  constexpr int kSegments = static_cast<int>(std::size(kAnchors)) - 1;
  for (int i = 0; i < 256; ++i) {
    const double t = i / 255.0 * kSegments;
    const int s = std::min(static_cast<int>(t), kSegments - 1);
    const double f = t - s;
    for (int c = 0; c < 3; ++c) {
      const double v = kAnchors[s][c] + f * (kAnchors[s + 1][c] - kAnchors[s][c]);
      table[i][c] = static_cast<std::uint8_t>(std::lround(v));
    }
  }
  return table;
}

}  // namespace

const std::array<Rgb, 256>& disparity_colours() {
  static const std::array<Rgb, 256> table = make_colours();
  return table;
}

void colour_disparity(ImageView<const std::int16_t> disparity16, int max_disparity,
                      std::uint8_t* rgb, std::size_t stride) {
  const std::array<Rgb, 256>& colours = disparity_colours();
  const int full = std::max(1, max_disparity * 16);
  for (int y = 0; y < disparity16.height(); ++y) {
    const std::int16_t* d = disparity16.row(y);
    std::uint8_t* out = rgb + static_cast<std::size_t>(y) * stride;
    for (int x = 0; x < disparity16.width(); ++x, out += 3) {
      if (d[x] < 0) {
        out[0] = out[1] = out[2] = 0;
        continue;
      }
      const Rgb& c = colours[static_cast<std::size_t>(
          std::min(d[x], static_cast<std::int16_t>(full)) * 255 / full)];
      out[0] = c[0];
      out[1] = c[1];
      out[2] = c[2];
    }
  }
}

}  // namespace epipole::firmware::view
