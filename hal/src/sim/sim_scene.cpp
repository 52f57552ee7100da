#include "sim/sim_scene.hpp"

#include <algorithm>
#include <cmath>
#include <vector>

namespace epipole::hal {

Letterbox letterbox_geometry(int from_width, int from_height, int to_width, int to_height) {
  require(from_width > 0 && from_height > 0 && to_width > 0 && to_height > 0, "letterbox: sizes ",
          from_width, "x", from_height, " -> ", to_width, "x", to_height, " must not be empty");
  Letterbox b;
  b.scale = std::min(static_cast<double>(to_width) / from_width,
                     static_cast<double>(to_height) / from_height);
  b.width = std::clamp(static_cast<int>(std::lround(from_width * b.scale)), 1, to_width);
  b.height = std::clamp(static_cast<int>(std::lround(from_height * b.scale)), 1, to_height);
  b.x = (to_width - b.width) / 2;
  b.y = (to_height - b.height) / 2;
  return b;
}

namespace {

// The weights of the source samples of each destination sample along one axis: area coverage
// when shrinking, linear interpolation when growing.
struct Taps {
  std::vector<int> first;      // per destination sample: first source sample
  std::vector<int> count;      // and how many
  std::vector<float> weights;  // count per destination, flattened, each set summing to 1
  std::vector<std::size_t> start;
};

Taps taps(int from, int to) {
  Taps t;
  const double scale = static_cast<double>(from) / to;  // source samples per destination
  for (int i = 0; i < to; ++i) {
    t.start.push_back(t.weights.size());
    if (scale >= 1) {
      const double a = i * scale;
      const double b = a + scale;
      const int first = static_cast<int>(std::floor(a));
      const int last = std::min(from - 1, static_cast<int>(std::ceil(b)) - 1);
      t.first.push_back(first);
      t.count.push_back(last - first + 1);
      for (int s = first; s <= last; ++s) {
        const double cover = std::min<double>(b, s + 1) - std::max<double>(a, s);
        t.weights.push_back(static_cast<float>(cover / scale));
      }
    } else {
      const double centre = (i + 0.5) * scale - 0.5;
      const int s0 = std::clamp(static_cast<int>(std::floor(centre)), 0, from - 1);
      const int s1 = std::min(s0 + 1, from - 1);
      const double f = std::clamp(centre - s0, 0.0, 1.0);
      t.first.push_back(s0);
      t.count.push_back(s1 > s0 ? 2 : 1);
      if (s1 > s0) {
        t.weights.push_back(static_cast<float>(1 - f));
        t.weights.push_back(static_cast<float>(f));
      } else {
        t.weights.push_back(1.0f);
      }
    }
  }
  return t;
}

}  // namespace

GrayImage letterbox(GrayView image, int width, int height, std::uint8_t fill) {
  const Letterbox b = letterbox_geometry(image.width(), image.height(), width, height);
  GrayImage out(width, height);
  for (int y = 0; y < height; ++y) std::fill_n(out.view().row(y), width, fill);
  if (b.width == image.width() && b.height == image.height()) {
    for (int y = 0; y < image.height(); ++y) {
      std::copy_n(image.row(y), image.width(), out.view().row(y + b.y) + b.x);
    }
    return out;
  }
  const Taps tx = taps(image.width(), b.width);
  const Taps ty = taps(image.height(), b.height);
  std::vector<float> row(static_cast<std::size_t>(image.width()));
  for (int y = 0; y < b.height; ++y) {
    std::fill(row.begin(), row.end(), 0.0f);
    const std::size_t yi = static_cast<std::size_t>(y);
    for (int k = 0; k < ty.count[yi]; ++k) {
      const float w = ty.weights[ty.start[yi] + static_cast<std::size_t>(k)];
      const std::uint8_t* src = image.row(ty.first[yi] + k);
      for (int x = 0; x < image.width(); ++x) row[static_cast<std::size_t>(x)] += w * src[x];
    }
    std::uint8_t* dst = out.view().row(y + b.y) + b.x;
    for (int x = 0; x < b.width; ++x) {
      const std::size_t xi = static_cast<std::size_t>(x);
      float v = 0;
      for (int k = 0; k < tx.count[xi]; ++k) {
        v += tx.weights[tx.start[xi] + static_cast<std::size_t>(k)] *
             row[static_cast<std::size_t>(tx.first[xi] + k)];
      }
      dst[x] = static_cast<std::uint8_t>(std::clamp(std::lround(v), 0L, 255L));
    }
  }
  return out;
}

GrayImage synthesize_right(GrayView left, int disparity) {
  require(!left.empty(), "synthesize_right: the left image is empty");
  require(disparity >= 0 && disparity < left.width(), "synthesize_right: disparity ", disparity,
          " is outside 0..", left.width() - 1);
  GrayImage right(left.width(), left.height());
  for (int y = 0; y < left.height(); ++y) {
    const std::uint8_t* in = left.row(y);
    std::uint8_t* out = right.view().row(y);
    for (int x = 0; x < left.width(); ++x) out[x] = in[std::min(x + disparity, left.width() - 1)];
  }
  return right;
}

}  // namespace epipole::hal
