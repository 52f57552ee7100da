#include "epipole/vision/patch_alignment.hpp"

#include <array>
#include <cmath>

namespace epipole::vision {

namespace {

constexpr int kMaxRadius = 7;
constexpr int kMaxPixels = (2 * kMaxRadius + 1) * (2 * kMaxRadius + 1);

// Zero mean and unit variance over n values; false when they are flat.
bool normalise(float* v, int n) {
  float sum = 0, squares = 0;
  for (int i = 0; i < n; ++i) sum += v[i];
  const float mean = sum / static_cast<float>(n);
  for (int i = 0; i < n; ++i) {
    const float c = v[i] - mean;
    squares += c * c;
  }
  if (!(squares > 0)) return false;
  const float scale = std::sqrt(static_cast<float>(n) / squares);
  for (int i = 0; i < n; ++i) v[i] = (v[i] - mean) * scale;
  return true;
}

}  // namespace

PatchOffset align_patch(GrayView left, int xl, int yl, GrayView right, float xr, float yr,
                        const PatchAlignmentConfig& config) {
  PatchOffset out;
  const int r = config.radius;
  if (r < 1 || r > kMaxRadius) return out;
  const int side = 2 * r + 1;
  const int n = side * side;
  // The left patch and its gradients (central differences: one pixel more each side).
  if (xl - r - 1 < 0 || yl - r - 1 < 0 || xl + r + 1 >= left.width() ||
      yl + r + 1 >= left.height()) {
    return out;
  }
  std::array<float, kMaxPixels> t{}, gx{}, gy{}, sample{};
  for (int j = -r, k = 0; j <= r; ++j) {
    const std::uint8_t* row = left.row(yl + j);
    const std::uint8_t* above = left.row(yl + j - 1);
    const std::uint8_t* below = left.row(yl + j + 1);
    for (int i = -r; i <= r; ++i, ++k) {
      const int x = xl + i;
      t[k] = row[x];
      gx[k] = 0.5f * static_cast<float>(row[x + 1] - row[x - 1]);
      gy[k] = 0.5f * static_cast<float>(below[x] - above[x]);
    }
  }
  // Normalising the patch scales its gradients alike.
  double sum = 0, squares = 0;
  for (int k = 0; k < n; ++k) sum += static_cast<double>(t[k]);
  for (int k = 0; k < n; ++k) {
    const double c = static_cast<double>(t[k]) - sum / n;
    squares += c * c;
  }
  if (squares <= 0) return out;
  const double gradient_scale = std::sqrt(n / squares);
  double hxx = 0, hxy = 0, hyy = 0, raw_xx = 0, raw_xy = 0, raw_yy = 0;
  for (int k = 0; k < n; ++k) {
    const auto x = static_cast<double>(gx[k]), y = static_cast<double>(gy[k]);
    raw_xx += x * x;
    raw_xy += x * y;
    raw_yy += y * y;
  }
  // The weaker direction: the smaller eigenvalue of the gradients' 2x2 matrix.
  const double half_trace = (raw_xx + raw_yy) / 2;
  const double weakest =
      half_trace - std::sqrt((raw_xx - raw_yy) * (raw_xx - raw_yy) / 4 + raw_xy * raw_xy);
  if (weakest / n < static_cast<double>(config.min_gradient)) return out;
  const double s2 = gradient_scale * gradient_scale;
  hxx = raw_xx * s2;
  hxy = raw_xy * s2;
  hyy = raw_yy * s2;
  const double det = hxx * hyy - hxy * hxy;
  normalise(t.data(), n);

  const double start_x = static_cast<double>(xr) - xl, start_y = static_cast<double>(yr) - yl;
  double dx = start_x, dy = start_y;
  for (int iteration = 0; iteration < config.iterations; ++iteration) {
    // The right patch at (xl + i + dx, yl + j + dy), bilinear.
    const double x0 = std::floor(xl + dx), y0 = std::floor(yl + dy);
    const double fx = xl + dx - x0, fy = yl + dy - y0;
    const int ix = static_cast<int>(x0), iy = static_cast<int>(y0);
    if (ix - r < 0 || iy - r < 0 || ix + r + 1 >= right.width() || iy + r + 1 >= right.height()) {
      return out;
    }
    const auto w00 = static_cast<float>((1 - fx) * (1 - fy)),
               w10 = static_cast<float>(fx * (1 - fy));
    const auto w01 = static_cast<float>((1 - fx) * fy), w11 = static_cast<float>(fx * fy);
    for (int j = -r, k = 0; j <= r; ++j) {
      const std::uint8_t* top = right.row(iy + j);
      const std::uint8_t* bottom = right.row(iy + j + 1);
      for (int i = -r; i <= r; ++i, ++k) {
        const int x = ix + i;
        sample[k] = w00 * top[x] + w10 * top[x + 1] + w01 * bottom[x] + w11 * bottom[x + 1];
      }
    }
    if (!normalise(sample.data(), n)) return out;
    float sum_x = 0, sum_y = 0, sum_c = 0;
    for (int k = 0; k < n; ++k) {
      const float e = sample[k] - t[k];
      sum_x += gx[k] * e;
      sum_y += gy[k] * e;
      sum_c += sample[k] * t[k];
    }
    const double bx = static_cast<double>(sum_x) * gradient_scale;
    const double by = static_cast<double>(sum_y) * gradient_scale;
    const auto correlation = static_cast<double>(sum_c);
    // Inverse compositional: the template's step, undone on the right patch's position.
    const double step_x = (hyy * bx - hxy * by) / det;
    const double step_y = (hxx * by - hxy * bx) / det;
    dx -= step_x;
    dy -= step_y;
    if (std::hypot(dx - start_x, dy - start_y) > static_cast<double>(config.max_travel)) {
      return out;
    }
    if (std::hypot(step_x, step_y) < 1e-3) {
      out.dx = static_cast<float>(dx);
      out.dy = static_cast<float>(dy);
      out.ncc = static_cast<float>(correlation / n);
      out.found = out.ncc >= config.min_ncc;
      return out;
    }
  }
  return out;
}

}  // namespace epipole::vision
