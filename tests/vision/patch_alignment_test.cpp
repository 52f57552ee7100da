// Patch alignment: sub-pixel offsets of a smooth texture shifted by known amounts, between
// cameras of different gain and offset, with sensor noise; patches that cannot say where they
// are (flat, one edge, at the border, too far) are not found.
#include "epipole/vision/patch_alignment.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <random>
#include <vector>

namespace epipole::vision {
namespace {

// A smooth texture: a sum of sines of random directions and wavelengths from 5 to 30 pixels.
class Texture {
 public:
  explicit Texture(unsigned seed) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> angle(0, 2 * M_PI), wavelength(5, 30), phase(0, 6.3);
    for (Wave& w : waves_) {
      const double a = angle(rng), k = 2 * M_PI / wavelength(rng);
      w = {k * std::cos(a), k * std::sin(a), phase(rng)};
    }
  }
  double operator()(double x, double y) const {
    double v = 0;
    for (const Wave& w : waves_) v += std::sin(w.kx * x + w.ky * y + w.phase);
    return 128 + 90 * v / std::sqrt(static_cast<double>(waves_.size()) / 2) / 2;
  }

 private:
  struct Wave {
    double kx, ky, phase;
  };
  std::array<Wave, 12> waves_{};
};

// The texture at (x - dx, y - dy) times gain plus offset, with Gaussian noise: what lies at
// (x, y) in the left image lies at (x + dx, y + dy) in this one.
GrayImage render(const Texture& texture, int w, int h, double dx, double dy, double gain,
                 double offset, double noise, unsigned seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> n(0, noise > 0 ? noise : 1);
  GrayImage image(w, h);
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      double v = gain * texture(x - dx, y - dy) + offset + (noise > 0 ? n(rng) : 0);
      image(x, y) = static_cast<std::uint8_t>(std::clamp(std::lround(v), 0L, 255L));
    }
  }
  return image;
}

struct Errors {
  int found = 0, tried = 0;
  double mean_abs_dy = 0, mean_dy = 0, worst_dy = 0;
};

// Aligns a grid of patches, each started from the true position rounded to whole pixels.
Errors align_grid(const GrayImage& left, const GrayImage& right, double dx, double dy) {
  Errors e;
  constexpr int kMargin = 12;  // the patch's radius, its gradients' pixel and the rounding
  for (int y = kMargin; y < left.height() - kMargin; y += 9) {
    for (int x = kMargin; x < left.width() - kMargin; x += 9) {
      if (x + dx < kMargin || x + dx >= left.width() - kMargin || y + dy < kMargin ||
          y + dy >= left.height() - kMargin) {
        continue;  // the right patch leaves the image
      }
      ++e.tried;
      const auto xr = static_cast<float>(std::round(x + dx));
      const auto yr = static_cast<float>(std::round(y + dy));
      const PatchOffset o = align_patch(left.view(), x, y, right.view(), xr, yr);
      if (!o.found) continue;
      ++e.found;
      const double error = static_cast<double>(o.dy) - dy;
      e.mean_abs_dy += std::abs(error);
      e.mean_dy += error;
      e.worst_dy = std::max(e.worst_dy, std::abs(error));
      EXPECT_NEAR(o.dx, dx, 0.1) << x << "," << y;
    }
  }
  if (e.found > 0) {
    e.mean_abs_dy /= e.found;
    e.mean_dy /= e.found;
  }
  return e;
}

TEST(PatchAlignment, FindsSubPixelOffsetsOfAShiftedTexture) {
  for (const auto& [dx, dy] : {std::pair{-6.3, 0.13}, std::pair{-12.0, -0.37}, std::pair{-3.5, 0.5},
                               std::pair{-20.71, -1.24}, std::pair{0.0, 0.02}}) {
    const Texture texture(3);
    const GrayImage left = render(texture, 160, 120, 0, 0, 1, 0, 0, 1);
    const GrayImage right = render(texture, 160, 120, dx, dy, 1, 0, 0, 2);
    const Errors e = align_grid(left, right, dx, dy);
    EXPECT_GE(e.found, e.tried * 95 / 100) << dx << "," << dy;
    EXPECT_LT(e.mean_abs_dy, 0.02) << dx << "," << dy;
    EXPECT_LT(e.worst_dy, 0.08) << dx << "," << dy;
  }
}

TEST(PatchAlignment, GainOffsetAndNoiseLeaveNoBias) {
  for (const unsigned seed : {5u, 9u}) {
    const Texture texture(seed);
    const double dx = -9.6, dy = 0.29;
    const GrayImage left = render(texture, 200, 150, 0, 0, 1, 0, 2, seed);
    const GrayImage right = render(texture, 200, 150, dx, dy, 0.8, 25, 2, seed + 100);
    const Errors e = align_grid(left, right, dx, dy);
    EXPECT_GE(e.found, e.tried * 8 / 10) << seed;
    EXPECT_LT(e.mean_abs_dy, 0.06) << seed;
    EXPECT_LT(std::abs(e.mean_dy), 0.02) << seed << ": the mean is (nearly) unbiased";
  }
}

TEST(PatchAlignment, PatchesThatCannotSayWhereTheyAreAreNotFound) {
  GrayImage flat(64, 64), edge(64, 64);
  for (int y = 0; y < 64; ++y) {
    for (int x = 0; x < 64; ++x) {
      flat(x, y) = 100;
      edge(x, y) = x < 32 ? 40 : 200;  // a vertical edge: nothing says where along it
    }
  }
  EXPECT_FALSE(align_patch(flat.view(), 32, 32, flat.view(), 32, 32).found);
  EXPECT_FALSE(align_patch(edge.view(), 32, 32, edge.view(), 32, 32).found);
  const Texture texture(4);
  const GrayImage image = render(texture, 64, 64, 0, 0, 1, 0, 0, 1);
  EXPECT_TRUE(align_patch(image.view(), 32, 32, image.view(), 32, 32).found);
  // At the border, either image's.
  EXPECT_FALSE(align_patch(image.view(), 3, 32, image.view(), 32, 32).found);
  EXPECT_FALSE(align_patch(image.view(), 32, 32, image.view(), 61, 32).found);
  EXPECT_FALSE(align_patch(image.view(), 32, 60, image.view(), 32, 32).found);
  // Another patch far from where it started: travelled too far, or unlike it.
  const GrayImage far = render(texture, 64, 64, 0, 4, 1, 0, 0, 1);
  EXPECT_FALSE(align_patch(image.view(), 32, 32, far.view(), 32, 32).found);
  // Radii outside 1..7.
  EXPECT_FALSE(align_patch(image.view(), 32, 32, image.view(), 32, 32, {.radius = 0}).found);
  EXPECT_FALSE(align_patch(image.view(), 32, 32, image.view(), 32, 32, {.radius = 8}).found);
}

}  // namespace
}  // namespace epipole::vision
