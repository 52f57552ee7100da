#include "synthetic_stereo.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <random>

#include "epipole/core/error.hpp"
#include "epipole/core/image_io.hpp"
#include "test_data.hpp"

namespace epipole::test {

namespace {

// A texture stretched over the whole scene, sampled bilinearly; `contrast` scales it about its
// mean (low-texture surfaces).
class Texture {
 public:
  Texture(const std::string& sample, int width, int height, double contrast = 1.0)
      : image_(load_gray(data_file("samples/" + sample))),
        sx_(static_cast<double>(image_.width() - 1) / width),
        sy_(static_cast<double>(image_.height() - 1) / height),
        contrast_(contrast) {
    double sum = 0;
    for (int y = 0; y < image_.height(); ++y) {
      for (int x = 0; x < image_.width(); ++x) sum += image_(x, y);
    }
    mean_ = sum / (static_cast<double>(image_.width()) * image_.height());
  }
  std::uint8_t at(double u, double v) const {
    const double tx = std::clamp(u * sx_, 0.0, image_.width() - 1.0);
    const double ty = std::clamp(v * sy_, 0.0, image_.height() - 1.0);
    const int x0 = std::min(static_cast<int>(tx), image_.width() - 2);
    const int y0 = std::min(static_cast<int>(ty), image_.height() - 2);
    const double fx = tx - x0, fy = ty - y0;
    const double top = image_(x0, y0) * (1 - fx) + image_(x0 + 1, y0) * fx;
    const double bottom = image_(x0, y0 + 1) * (1 - fx) + image_(x0 + 1, y0 + 1) * fx;
    const double value = mean_ + contrast_ * (top * (1 - fy) + bottom * fy - mean_);
    return static_cast<std::uint8_t>(std::clamp(std::lround(value), 0L, 255L));
  }

 private:
  GrayImage image_;
  double sx_, sy_, contrast_, mean_ = 0;
};

// A planar surface: disparity a*x + b*y + c at left-view pixel (x, y), over [x0, x1) x [y0, y1)
// of the left view.
struct Surface {
  double a = 0, b = 0, c = 0;
  double x0 = -1e9, x1 = 1e9, y0 = -1e9, y1 = 1e9;
  std::shared_ptr<const Texture> texture;

  double disparity(double x, double y) const { return a * x + b * y + c; }
  bool covers(double x, double y) const { return x >= x0 && x < x1 && y >= y0 && y < y1; }
  // The left-view x of the surface point seen at right-view x' (x' = x - d(x, y)).
  double left_x(double right_x, double y) const { return (right_x + b * y + c) / (1 - a); }
};

struct Hit {
  const Surface* surface = nullptr;
  double x = 0;  // the surface point's left-view x
  double disparity = -std::numeric_limits<double>::infinity();
};

Hit nearest_in_left(const std::vector<Surface>& scene, double x, double y) {
  Hit hit;
  for (const Surface& s : scene) {
    const double d = s.disparity(x, y);
    if (s.covers(x, y) && d > hit.disparity) hit = {&s, x, d};
  }
  return hit;
}

Hit nearest_in_right(const std::vector<Surface>& scene, double right_x, double y) {
  Hit hit;
  for (const Surface& s : scene) {
    const double x = s.left_x(right_x, y);
    const double d = s.disparity(x, y);
    if (s.covers(x, y) && d > hit.disparity) hit = {&s, x, d};
  }
  return hit;
}

// Two real cameras differ: the right one here has 8 % less gain and an offset of 6 levels, and
// each pixel of each view has its own noise of up to 3 levels (std::mt19937's sequence, the same
// everywhere).
void add_camera_effects(SyntheticPair& p, unsigned seed) {
  std::mt19937 noise(seed);
  const auto level = [&](double v) {
    const int n = static_cast<int>(noise() % 7) - 3;
    return static_cast<std::uint8_t>(std::clamp(std::lround(v) + n, 0L, 255L));
  };
  for (int y = 0; y < p.left.height(); ++y) {
    for (int x = 0; x < p.left.width(); ++x) {
      p.left(x, y) = level(p.left(x, y));
      p.right(x, y) = level(0.92 * p.right(x, y) + 6);
    }
  }
}

SyntheticPair render(const std::string& name, const std::vector<Surface>& scene, int width,
                     int height, unsigned noise_seed) {
  SyntheticPair p{name, GrayImage(width, height), GrayImage(width, height),
                  Image<float>(width, height), GrayImage(width, height)};
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < width; ++x) {
      const Hit left = nearest_in_left(scene, x, y);
      require(left.surface != nullptr, "synthetic scene ", name, ": nothing at (", x, ", ", y, ")");
      p.left(x, y) = left.surface->texture->at(left.x, y);
      p.truth(x, y) = static_cast<float>(left.disparity);
      // Seen in the right view where no nearer surface covers the point and it is inside it.
      const double right_x = x - left.disparity;
      const Hit seen = nearest_in_right(scene, right_x, y);
      const bool visible = right_x >= 0 && right_x <= width - 1 && seen.surface == left.surface;
      p.nonoccluded(x, y) = visible ? 255 : 128;
      const Hit right = nearest_in_right(scene, x, y);
      require(right.surface != nullptr, "synthetic scene ", name, ": nothing at right (", x, ", ",
              y, ")");
      p.right(x, y) = right.surface->texture->at(right.x, y);
    }
  }
  add_camera_effects(p, noise_seed);
  return p;
}

std::vector<Surface> scene_surfaces(const std::string& name, int width, int height) {
  const auto texture = [&](const char* sample, double contrast = 1.0) {
    return std::make_shared<const Texture>(sample, width, height, contrast);
  };
  const double w = width, h = height;
  const auto box = [&](double x0, double y0, double x1, double y1, double d, auto t) {
    Surface s;
    s.c = d;
    s.x0 = x0 * w, s.x1 = x1 * w, s.y0 = y0 * h, s.y1 = y1 * h;
    s.texture = std::move(t);
    return s;
  };
  // Disparities scale with the width (a wider image of the same rig).
  const double k = w / 640.0;
  if (name == "fronto") {
    return {box(-1, -1, 2, 2, 37.25 * k, texture("graf1.png"))};
  }
  if (name == "slanted") {
    Surface s = box(-1, -1, 2, 2, 10 * k, texture("building.jpg"));
    s.a = 0.1;
    s.b = 0.05 * k;
    return {s};
  }
  if (name == "boxes") {
    return {box(-1, -1, 2, 2, 16 * k, texture("graf1.png")),
            box(0.15, 0.15, 0.35, 0.55, 48 * k, texture("baboon.jpg")),
            box(0.45, 0.4, 0.65, 0.8, 72 * k, texture("fruits.jpg")),
            box(0.72, 0.12, 0.95, 0.42, 96 * k, texture("starry_night.jpg"))};
  }
  if (name == "low-texture") {
    return {box(-1, -1, 2, 2, 20 * k, texture("graf1.png")),
            box(0.25, 0.2, 0.8, 0.8, 45 * k, texture("home.jpg", 1.0 / 16))};
  }
  if (name == "thin") {
    std::vector<Surface> s{box(-1, -1, 2, 2, 20 * k, texture("leuvenA.jpg"))};
    const auto bars = texture("baboon.jpg");
    for (int i = 0; i < 6; ++i) {  // vertical bars 2, 3 and 4 px wide
      const double x0 = (0.1 + 0.14 * i) * w, bar = 2 + i % 3;
      s.push_back(box(x0 / w, 0.1, (x0 + bar) / w, 0.9, 60 * k, bars));
    }
    for (int i = 0; i < 3; ++i) {  // wires 2 and 3 px high
      const double y0 = (0.25 + 0.25 * i) * h, wire = 2 + i % 2;
      s.push_back(box(0.05, y0 / h, 0.95, (y0 + wire) / h, 84 * k, bars));
    }
    return s;
  }
  throw Error(cat("no synthetic scene '", name, "'"));
}

}  // namespace

std::vector<std::string> synthetic_scene_names() {
  return {"fronto", "slanted", "boxes", "low-texture", "thin"};
}

SyntheticPair synthetic_scene(const std::string& name, int width, int height, unsigned noise_seed) {
  return render(name, scene_surfaces(name, width, height), width, height, noise_seed);
}

}  // namespace epipole::test
