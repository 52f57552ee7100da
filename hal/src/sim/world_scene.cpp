// The simulated board's rendered world (world_scene.hpp): rays cast through the rig's
// calibration into a floor, a wall and boxes, their photos sampled from mip pyramids, sensor
// noise added; and the exact truth of the same geometry. Start-up code (allocations are fine).
#include "sim/world_scene.hpp"

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <exception>
#include <limits>
#include <memory>
#include <mutex>
#include <numbers>
#include <sstream>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include "epipole/calib/disparity_plane.hpp"
#include "epipole/core/angles.hpp"
#include "epipole/core/error.hpp"
#include "epipole/core/image_io.hpp"
#include "epipole/core/splitmix.hpp"
#include "epipole/core/text_file.hpp"

namespace epipole::hal {

namespace {

constexpr double kWorldNearestHit = 1e-9;  // along a ray: nearer hits are none
constexpr double kWorldMinCosine = 0.05;   // bounds a grazing surface's stretch of a footprint
constexpr double kWorldFarTexels = 1e12;   // beyond: a photo's mean (its pyramid's top)

// ---------------------------------------------------------------------------------------------
// Geometry: the cameras in the world and the surface a ray meets first.

// A camera in the world: its optical centre and its frame's axes (the columns of to_world).
struct WorldView {
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();
  Eigen::Matrix3d to_world = Eigen::Matrix3d::Identity();
};

WorldView left_camera_view(const RigPose& pose) {
  const double yaw = radians(pose.yaw_deg);
  const double pitch = radians(pose.pitch_deg);
  const double roll = radians(pose.roll_deg);
  const Eigen::Vector3d up(0.0, 1.0, 0.0);
  const Eigen::Vector3d heading(std::sin(yaw), 0.0, std::cos(yaw));
  const Eigen::Vector3d right(std::cos(yaw), 0.0, -std::sin(yaw));
  // Pitched down: z towards the floor, y (down in the image) towards the rig's back.
  const Eigen::Vector3d z = std::cos(pitch) * heading - std::sin(pitch) * up;
  const Eigen::Vector3d y = -std::cos(pitch) * up - std::sin(pitch) * heading;
  WorldView view;
  view.centre = Eigen::Vector3d(pose.x_m, pose.height_m, pose.z_m);
  // Rolled about z: positive turns x (the image's right) towards y (down).
  view.to_world.col(0) = std::cos(roll) * right + std::sin(roll) * y;
  view.to_world.col(1) = -std::sin(roll) * right + std::cos(roll) * y;
  view.to_world.col(2) = z;
  return view;
}

// The right camera, where the calibration puts it: x_right = R x_left + T, so its centre is
// -R^T T in the left frame and its directions d are R^T d there.
WorldView right_camera_view(const WorldView& left, const calib::StereoCalibration& rig) {
  const Eigen::Matrix3d right_to_left = rig.R.transpose();
  WorldView view;
  view.centre = left.centre - left.to_world * (right_to_left * rig.T);
  view.to_world = left.to_world * right_to_left;
  return view;
}

// The surfaces: the floor, the wall, then the boxes.
constexpr int kFloorSurface = 0;
constexpr int kWallSurface = 1;
constexpr int kFirstBoxSurface = 2;

// The nearest surface a ray meets: t along the ray (in units of its direction), the surface
// (-1: none) and the world axis of the normal of the face met (the floor's Y, the wall's Z).
struct WorldHit {
  double t = std::numeric_limits<double>::infinity();
  int surface = -1;
  int axis = 1;
};

// The slab test: the face through which the ray enters the box, when nearer than `nearest`.
void hit_world_box(const WorldBox& box, int surface, const Eigen::Vector3d& origin,
                   const Eigen::Vector3d& dir, WorldHit& nearest) {
  const std::array<double, 3> lo{box.x_m - box.width_m / 2, 0.0, box.z_m};
  const std::array<double, 3> hi{box.x_m + box.width_m / 2, box.height_m, box.z_m + box.depth_m};
  double t_in = -std::numeric_limits<double>::infinity();
  double t_out = std::numeric_limits<double>::infinity();
  int axis = -1;
  for (int a = 0; a < 3; ++a) {
    const double o = origin[a];
    const double d = dir[a];
    if (d == 0) {
      if (o < lo[a] || o > hi[a]) return;  // parallel to the slab, outside it
      continue;
    }
    double t0 = (lo[a] - o) / d;
    double t1 = (hi[a] - o) / d;
    if (t0 > t1) std::swap(t0, t1);
    if (t0 > t_in) {
      t_in = t0;
      axis = a;
    }
    t_out = std::min(t_out, t1);
  }
  // Missed, behind, from inside (no face seen) or hidden.
  if (axis < 0 || t_in > t_out || t_in <= kWorldNearestHit || t_in >= nearest.t) return;
  nearest = {t_in, surface, axis};
}

WorldHit cast_world_ray(const SimWorld& world, const Eigen::Vector3d& origin,
                        const Eigen::Vector3d& dir) {
  WorldHit nearest;
  if (dir.y() != 0) {
    const double t = -origin.y() / dir.y();
    if (t > kWorldNearestHit) nearest = {t, kFloorSurface, 1};
  }
  if (world.wall && dir.z() != 0) {
    const double t = (world.wall->distance_m - origin.z()) / dir.z();
    if (t > kWorldNearestHit && t < nearest.t) nearest = {t, kWallSurface, 2};
  }
  for (std::size_t i = 0; i < world.boxes.size(); ++i) {
    hit_world_box(world.boxes[i], kFirstBoxSurface + static_cast<int>(i), origin, dir, nearest);
  }
  return nearest;
}

// ---------------------------------------------------------------------------------------------
// Photos: mip pyramids, sampled trilinearly with mirrored repeat.

struct MipLevel {
  int width = 0;
  int height = 0;
  std::vector<float> texels;  // row by row

  std::size_t index(int x, int y) const {
    return static_cast<std::size_t>(y) * static_cast<std::size_t>(width) +
           static_cast<std::size_t>(x);
  }
  double at(int x, int y) const { return static_cast<double>(texels[index(x, y)]); }
};
// Level 0 the photo, each next one the 2x2 averages of the one before (a last odd row or
// column averaged with itself), down to 1x1.
using MipPyramid = std::vector<MipLevel>;

MipPyramid mip_pyramid(GrayView photo) {
  MipPyramid levels(1);
  MipLevel& base = levels.front();
  base.width = photo.width();
  base.height = photo.height();
  base.texels.resize(static_cast<std::size_t>(base.width) * static_cast<std::size_t>(base.height));
  for (int y = 0; y < base.height; ++y) {
    for (int x = 0; x < base.width; ++x) {
      base.texels[base.index(x, y)] = static_cast<float>(photo(x, y));
    }
  }
  while (levels.back().width > 1 || levels.back().height > 1) {
    const MipLevel& from = levels.back();
    MipLevel next;
    next.width = std::max(1, from.width / 2);
    next.height = std::max(1, from.height / 2);
    next.texels.resize(static_cast<std::size_t>(next.width) *
                       static_cast<std::size_t>(next.height));
    for (int y = 0; y < next.height; ++y) {
      const int y0 = std::min(2 * y, from.height - 1);
      const int y1 = std::min(2 * y + 1, from.height - 1);
      for (int x = 0; x < next.width; ++x) {
        const int x0 = std::min(2 * x, from.width - 1);
        const int x1 = std::min(2 * x + 1, from.width - 1);
        const double mean =
            0.25 * (from.at(x0, y0) + from.at(x1, y0) + from.at(x0, y1) + from.at(x1, y1));
        next.texels[next.index(x, y)] = static_cast<float>(mean);
      }
    }
    levels.push_back(std::move(next));
  }
  return levels;
}

// Texel i of a row (or column) of n tiled with mirrored repeat: 0..n-1, n-1..0, 0..n-1, ...
int mirrored_texel(int i, int n) {
  const int period = 2 * n;
  int m = i % period;
  if (m < 0) m += period;
  return m < n ? m : period - 1 - m;
}

// Bilinear at (u, v), in the level's texels (texel centres at +0.5).
double sample_level_bilinear(const MipLevel& level, double u, double v) {
  const double period_x = 2.0 * level.width;
  const double period_y = 2.0 * level.height;
  // Into one period first, so that far coordinates stay small integers.
  const double x = u - period_x * std::floor(u / period_x) - 0.5;
  const double y = v - period_y * std::floor(v / period_y) - 0.5;
  const double floor_x = std::floor(x);
  const double floor_y = std::floor(y);
  const double ax = x - floor_x;
  const double ay = y - floor_y;
  const int x0 = static_cast<int>(floor_x);
  const int y0 = static_cast<int>(floor_y);
  const int xa = mirrored_texel(x0, level.width);
  const int xb = mirrored_texel(x0 + 1, level.width);
  const int ya = mirrored_texel(y0, level.height);
  const int yb = mirrored_texel(y0 + 1, level.height);
  return (1 - ay) * ((1 - ax) * level.at(xa, ya) + ax * level.at(xb, ya)) +
         ay * ((1 - ax) * level.at(xa, yb) + ax * level.at(xb, yb));
}

// Trilinear at (u, v) in level 0's texels; lod: log2 of the footprint in level 0's texels.
// Each level is addressed at its own scale of the photo (an odd size halves to a slightly
// smaller photo), so every level tiles with level 0's period.
double sample_photo(const MipPyramid& levels, double u, double v, double lod) {
  const int top = static_cast<int>(levels.size()) - 1;
  if (!(std::abs(u) < kWorldFarTexels && std::abs(v) < kWorldFarTexels) || !(lod < top)) {
    return levels.back().at(0, 0);
  }
  const MipLevel& base = levels.front();
  const auto at_level = [&](int l) {
    const MipLevel& level = levels[static_cast<std::size_t>(l)];
    return sample_level_bilinear(level, u * level.width / base.width,
                                 v * level.height / base.height);
  };
  const double clamped = std::max(lod, 0.0);
  const int l0 = static_cast<int>(std::floor(clamped));
  const double blend = clamped - l0;
  const double near_value = at_level(l0);
  if (blend <= 0) return near_value;
  return (1 - blend) * near_value + blend * at_level(l0 + 1);
}

// A surface's photo and the size of its texels.
struct WorldSurface {
  std::shared_ptr<const MipPyramid> photo;  // null: no such surface (no wall)
  double texel_m = 0;
};

// The surfaces' photos (each file read once), in the order of the surfaces.
std::vector<WorldSurface> load_world_surfaces(const SimWorld& world) {
  std::vector<std::pair<std::filesystem::path, std::shared_ptr<const MipPyramid>>> loaded;
  const auto surface_of = [&](const WorldTexture& texture) {
    std::shared_ptr<const MipPyramid> photo;
    for (const auto& [file, pyramid] : loaded) {
      if (file == texture.file) photo = pyramid;
    }
    if (!photo) {
      const GrayImage image = load_gray(texture.file);
      require(!image.empty(), texture.file.string(), ": the image is empty");
      photo = std::make_shared<const MipPyramid>(mip_pyramid(image.view()));
      loaded.emplace_back(texture.file, photo);
    }
    return WorldSurface{photo, texture.texel_mm / 1000};
  };
  std::vector<WorldSurface> surfaces;
  surfaces.push_back(surface_of(world.floor));
  surfaces.push_back(world.wall ? surface_of(world.wall->texture) : WorldSurface{});
  for (const WorldBox& box : world.boxes) surfaces.push_back(surface_of(box.texture));
  return surfaces;
}

// ---------------------------------------------------------------------------------------------
// Rendering.

// What a ray sees: its hit's photo filtered over the ray's footprint there (pixel_angle: the
// angle between neighbouring pixels' rays, radians); nothing hit is black.
double shade_world_ray(const SimWorld& world, const std::vector<WorldSurface>& surfaces,
                       const Eigen::Vector3d& origin, const Eigen::Vector3d& dir,
                       double pixel_angle) {
  const WorldHit hit = cast_world_ray(world, origin, dir);
  if (hit.surface < 0) return 0;
  const WorldSurface& surface = surfaces[static_cast<std::size_t>(hit.surface)];
  const MipLevel& base = surface.photo->front();
  const double photo_width_m = base.width * surface.texel_m;
  const double photo_height_m = base.height * surface.texel_m;
  const Eigen::Vector3d p = origin + hit.t * dir;
  // Where on the photo, metres: s along its rows (rightwards), r down its columns.
  double s = 0;
  double r = 0;
  if (hit.surface == kFloorSurface) {
    // Centred on X = 0, its bottom edge below the camera, upright seen from the rig.
    s = p.x() + photo_width_m / 2;
    r = photo_height_m - p.z();
  } else if (hit.surface == kWallSurface) {
    // Centred on X = 0, standing on the floor.
    s = p.x() + photo_width_m / 2;
    r = photo_height_m - p.y();
  } else {
    // The photo's top left corner at each face's (seen from the rig).
    const WorldBox& box = world.boxes[static_cast<std::size_t>(hit.surface - kFirstBoxSurface)];
    const double left_x = box.x_m - box.width_m / 2;
    if (hit.axis == 0) {  // a side
      s = p.z() - box.z_m;
      r = box.height_m - p.y();
    } else if (hit.axis == 1) {  // the top (or the bottom)
      s = p.x() - left_x;
      r = box.z_m + box.depth_m - p.z();
    } else {  // the front (or the back)
      s = p.x() - left_x;
      r = box.height_m - p.y();
    }
  }
  // The footprint, stretched along the surface by the incidence; the level's texels match it.
  const double length = dir.norm();
  const double cosine = std::abs(dir[hit.axis]) / length;
  const double footprint_m = hit.t * length * pixel_angle / std::max(cosine, kWorldMinCosine);
  return sample_photo(*surface.photo, s / surface.texel_m, r / surface.texel_m,
                      std::log2(footprint_m / surface.texel_m));
}

// The lens's normalised coordinates at the pixels' corners, (width + 1) x (height + 1), row by
// row: the corner before pixel (x, y) is at (x - 0.5, y - 0.5). The lens is smooth over half a
// pixel, so rays between the corners are interpolated from them (a quarter of the Newton
// inversions of the lens model, which were most of the rendering's time).
std::vector<Eigen::Vector2d> corner_rays(const calib::PinholeCamera& camera, int width,
                                         int height) {
  std::vector<Eigen::Vector2d> corners;
  corners.reserve(static_cast<std::size_t>(width + 1) * static_cast<std::size_t>(height + 1));
  for (int j = 0; j <= height; ++j) {
    for (int i = 0; i <= width; ++i) corners.push_back(camera.normalize({i - 0.5, j - 0.5}));
  }
  return corners;
}

// One camera's raw image, noise-free: each pixel the mean of 2x2 rays (+-0.25 pixels).
Image<float> render_world_view(const SimWorld& world, const std::vector<WorldSurface>& surfaces,
                               const WorldView& view, const calib::PinholeCamera& camera, int width,
                               int height) {
  constexpr std::array<double, 2> kSubPixel{-0.25, 0.25};
  const std::vector<Eigen::Vector2d> corners = corner_rays(camera, width, height);
  const auto corner = [&](int i, int j) -> const Eigen::Vector2d& {
    return corners[static_cast<std::size_t>(j) * static_cast<std::size_t>(width + 1) +
                   static_cast<std::size_t>(i)];
  };
  // Bilinear between the corners of pixel (x, y); NaN when one is outside the lens's domain.
  const auto ray = [&](int x, int y, double dx, double dy) {
    const double fx = 0.5 + dx, fy = 0.5 + dy;
    const Eigen::Vector2d top = (1 - fx) * corner(x, y) + fx * corner(x + 1, y);
    const Eigen::Vector2d bottom = (1 - fx) * corner(x, y + 1) + fx * corner(x + 1, y + 1);
    return Eigen::Vector2d((1 - fy) * top + fy * bottom);
  };
  Image<float> out(width, height);
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < width; ++x) {
      // Columns: (-,-), (+,-), (-,+), (+,+), in the camera frame (z = 1).
      Eigen::Matrix<double, 3, 4> rays = Eigen::Matrix<double, 3, 4>::Zero();
      std::array<bool, 4> inside{};
      int k = 0;
      for (const double dy : kSubPixel) {
        for (const double dx : kSubPixel) {
          const Eigen::Vector2d n = ray(x, y, dx, dy);
          inside[static_cast<std::size_t>(k)] = n.allFinite();
          rays.col(k) = Eigen::Vector3d(n.x(), n.y(), 1.0);
          ++k;
        }
      }
      // The sub-samples are half a pixel apart: the pixel's angle where the lens distorts it,
      // 1/fx where a ray is outside the lens's domain.
      double pixel_angle = 1 / camera.intrinsics.fx;
      if (inside[0] && inside[1] && inside[2]) {
        const Eigen::Vector3d a = rays.col(0).normalized();
        const double across = (rays.col(1).normalized() - a).norm();
        const double down = (rays.col(2).normalized() - a).norm();
        pixel_angle = 2 * std::max(across, down);
      }
      double sum = 0;
      for (int i = 0; i < 4; ++i) {
        if (!inside[static_cast<std::size_t>(i)]) continue;  // outside the lens: black
        const Eigen::Vector3d dir = view.to_world * rays.col(i);
        sum += shade_world_ray(world, surfaces, view.centre, dir, pixel_angle);
      }
      out(x, y) = static_cast<float>(sum / 4);
    }
  }
  return out;
}

// Gaussian noise, the same on every platform: splitmix64 and Box-Muller (std::normal_distribution
// differs between standard libraries).
class SensorNoise {
 public:
  explicit SensorNoise(std::uint64_t seed) : random_(seed) {}

  double gaussian() {
    if (has_spare_) {
      has_spare_ = false;
      return spare_;
    }
    const double u1 = 1.0 - uniform();  // (0, 1]
    const double u2 = uniform();
    const double radius = std::sqrt(-2.0 * std::log(u1));
    const double angle = 2.0 * std::numbers::pi * u2;
    spare_ = radius * std::sin(angle);
    has_spare_ = true;
    return radius * std::cos(angle);
  }

 private:
  double uniform() { return random_.uniform(); }  // [0, 1)

  SplitMix64 random_;
  double spare_ = 0;
  bool has_spare_ = false;
};

// The clean image with noise of `sigma` grey levels, rounded and clamped; `stream`: the frame
// and the camera (2 frame + camera), each its own noise.
GrayImage with_sensor_noise(const Image<float>& clean, double sigma, std::uint64_t stream) {
  SensorNoise noise(0x243f6a8885a308d3ULL ^ (stream * 0xd1b54a32d192ed03ULL));
  GrayImage out(clean.width(), clean.height());
  for (int y = 0; y < clean.height(); ++y) {
    for (int x = 0; x < clean.width(); ++x) {
      double v = static_cast<double>(clean(x, y));
      if (sigma > 0) v += sigma * noise.gaussian();
      out(x, y) = static_cast<std::uint8_t>(std::clamp(std::round(v), 0.0, 255.0));
    }
  }
  return out;
}

// A number of truth.yaml.
std::string truth_number(double v) {
  std::ostringstream out;
  out.precision(15);
  out << v;
  return out.str();
}

}  // namespace

StereoImages render_world(const SimWorld& world, const calib::StereoCalibration& rig, int width,
                          int height) {
  return render_world(world, world_poses(world), rig, width, height);
}

// The poses' pairs rendered on every core: each run of equal poses once, its noise per frame.
StereoImages render_world(const SimWorld& world, std::span<const RigPose> poses,
                          const calib::StereoCalibration& rig, int width, int height) {
  require(rig.width == width && rig.height == height,
          "the world is rendered through the calibration's cameras, of ", rig.width, "x",
          rig.height, ", but the simulated cameras are ", width, "x", height,
          ": give the scene a calibration of the cameras' size");
  require(!poses.empty(), "no pose of the rig to render the world from");
  calib::validate(rig);
  const std::vector<WorldSurface> surfaces = load_world_surfaces(world);
  std::vector<std::size_t> runs;  // the first frame of each run of equal poses
  for (std::size_t i = 0; i < poses.size(); ++i) {
    if (i == 0 || poses[i] != poses[i - 1]) runs.push_back(i);
  }
  StereoImages images;
  images.left.resize(poses.size());
  images.right.resize(poses.size());
  std::atomic<std::size_t> next_run{0};
  std::mutex failed_mutex;
  std::exception_ptr failed;  // the first worker's exception, thrown once all have stopped
  const auto render_all = [&] {
    for (std::size_t r = next_run++; r < runs.size(); r = next_run++) {
      const std::size_t end = r + 1 < runs.size() ? runs[r + 1] : poses.size();
      const WorldView view = left_camera_view(poses[runs[r]]);
      const Image<float> left =
          render_world_view(world, surfaces, view, rig.left.camera, width, height);
      const Image<float> right = render_world_view(world, surfaces, right_camera_view(view, rig),
                                                   rig.right.camera, width, height);
      for (std::size_t i = runs[r]; i < end; ++i) {
        images.left[i] = with_sensor_noise(left, world.noise, 2 * i);
        images.right[i] = with_sensor_noise(right, world.noise, 2 * i + 1);
      }
    }
  };
  const auto render_runs = [&] {
    try {
      render_all();
    } catch (...) {
      next_run = runs.size();  // the others stop after the run in hand
      const std::lock_guard lock(failed_mutex);
      if (!failed) failed = std::current_exception();
    }
  };
  {
    const std::size_t helpers =
        std::min<std::size_t>(std::max(1u, std::thread::hardware_concurrency()), runs.size()) - 1;
    std::vector<std::jthread> threads;
    threads.reserve(helpers);
    for (std::size_t t = 0; t < helpers; ++t) threads.emplace_back(render_runs);
    render_runs();
  }  // every worker joined before the images are used
  if (failed) std::rethrow_exception(failed);
  return images;
}

std::vector<calib::RigidMotion> world_trajectory(const SimWorld& world,
                                                 const calib::StereoCalibration& rig) {
  const std::vector<RigPose> poses = world_poses(world);
  // The rectified left camera's axes in the world: its directions d are R1^T d in the left's.
  const auto rectified = [&](const RigPose& pose) {
    const WorldView view = left_camera_view(pose);
    return calib::RigidMotion{view.to_world * rig.left.rectification.transpose(), view.centre};
  };
  const calib::RigidMotion first_inverse = rectified(poses.front()).inverse();
  std::vector<calib::RigidMotion> out;
  out.reserve(poses.size());
  for (const RigPose& pose : poses) out.push_back(first_inverse.after(rectified(pose)));
  return out;
}

GroundTruth ground_truth(const RigPose& pose, const calib::StereoCalibration& rig) {
  const WorldView view = left_camera_view(pose);
  const Eigen::Vector3d down(0.0, -1.0, 0.0);  // the floor's normal towards it, in the world
  GroundTruth truth;
  truth.normal_down = (rig.left.rectification * (view.to_world.transpose() * down)).normalized();
  truth.height_m = std::abs(view.centre.y());
  // The firmware's own definitions of a ground's pitch and roll (calib/disparity_plane.hpp).
  const calib::MetricPlane floor{truth.normal_down, truth.height_m};
  truth.pitch_deg = calib::pitch_deg(floor);
  truth.roll_deg = calib::roll_deg(floor);
  return truth;
}

GroundTruth world_ground_truth(const SimWorld& world, const calib::StereoCalibration& rig) {
  return ground_truth(world.rig, rig);
}

double disparity_of_depth(const calib::StereoCalibration& rig, double z) {
  const Eigen::Matrix4d& q = rig.Q;
  return q(2, 3) / (z * q(3, 2)) - q(3, 3) / q(3, 2);
}

TrueDepth world_true_depth(const SimWorld& world, const RigPose& pose,
                           const calib::StereoCalibration& rig) {
  calib::validate(rig);
  const WorldView view = left_camera_view(pose);
  const Eigen::Matrix3d rectified_to_world = view.to_world * rig.left.rectification.transpose();
  const Eigen::Matrix<double, 3, 4>& p1 = rig.left.projection;
  TrueDepth truth{Image<float>(rig.width, rig.height), Image<float>(rig.width, rig.height)};
  for (int v = 0; v < rig.height; ++v) {
    for (int u = 0; u < rig.width; ++u) {
      // The ray through the rectified pixel, its depth (rectified Z) 1 per unit of t.
      const Eigen::Vector3d ray((u - p1(0, 2)) / p1(0, 0), (v - p1(1, 2)) / p1(1, 1), 1.0);
      const WorldHit hit = cast_world_ray(world, view.centre, rectified_to_world * ray);
      if (hit.surface < 0) {
        truth.depth_m(u, v) = 0.0f;
        truth.disparity(u, v) = 0.0f;
        continue;
      }
      truth.depth_m(u, v) = static_cast<float>(hit.t);
      truth.disparity(u, v) = static_cast<float>(disparity_of_depth(rig, hit.t));
    }
  }
  return truth;
}

Image<float> world_true_disparity(const SimWorld& world, const calib::StereoCalibration& rig) {
  return world_true_depth(world, world.rig, rig).disparity;
}

void write_world_truth(const SimWorld& world, const calib::StereoCalibration& rig,
                       const std::filesystem::path& directory) {
  make_directories(directory);
  const GroundTruth ground = world_ground_truth(world, rig);
  const TrueDepth truth = world_true_depth(world, world.rig, rig);
  Image<std::uint16_t> disparity16(rig.width, rig.height);
  for (int y = 0; y < rig.height; ++y) {
    for (int x = 0; x < rig.width; ++x) {
      const double d = static_cast<double>(truth.disparity(x, y));
      disparity16(x, y) = 0;
      if (d > 0) {
        disparity16(x, y) =
            static_cast<std::uint16_t>(std::clamp(std::round(d * 16), 1.0, 65535.0));
      }
    }
  }
  save_image(directory / "true_disparity.png", std::as_const(disparity16).view());

  const auto n = [](double v) { return truth_number(v); };
  const RigPose& pose = world.rig;
  std::ostringstream yaml;
  yaml << "# The world scene's exact truth (hal/src/sim/world_scene.hpp).\n"
       << "# ground: the floor in the rectified left camera frame (R1 * left): normal_down, unit,\n"
       << "# from the camera towards the floor; height_m, the camera centre's distance from it;\n"
       << "# pitch_deg = asin(normal_down.z); roll_deg = atan2(normal_down.x, normal_down.y).\n"
       << "ground:\n"
       << "  normal_down: [" << n(ground.normal_down.x()) << ", " << n(ground.normal_down.y())
       << ", " << n(ground.normal_down.z()) << "]\n"
       << "  height_m: " << n(ground.height_m) << "\n"
       << "  pitch_deg: " << n(ground.pitch_deg) << "\n"
       << "  roll_deg: " << n(ground.roll_deg) << "\n"
       << "# The world: origin on the floor below the left camera, X right, Y up, Z forward.\n"
       << "rig: {height_m: " << n(pose.height_m) << ", pitch_deg: " << n(pose.pitch_deg)
       << ", roll_deg: " << n(pose.roll_deg) << ", x_m: " << n(pose.x_m) << ", z_m: " << n(pose.z_m)
       << ", yaw_deg: " << n(pose.yaw_deg) << "}\n";
  if (world.wall) yaml << "wall_distance_m: " << n(world.wall->distance_m) << "\n";
  yaml << "# Each box: its front face's Z and distance from the rig (along Z), its X range.\n"
       << "boxes:" << (world.boxes.empty() ? " []" : "") << "\n";
  for (const WorldBox& box : world.boxes) {
    yaml << "  - {front_z_m: " << n(box.z_m) << ", front_distance_m: " << n(box.z_m - pose.z_m)
         << ", x_range_m: [" << n(box.x_m - box.width_m / 2) << ", " << n(box.x_m + box.width_m / 2)
         << "], height_m: " << n(box.height_m) << ", depth_m: " << n(box.depth_m) << "}\n";
  }
  yaml << "# The rectified left view's disparity x 16 (16-bit PNG), 0 where nothing is hit.\n"
       << "true_disparity: true_disparity.png\n";
  if (world.path) {
    yaml << "# The rig's path: the rectified left camera's pose at each pair (TUM: seconds from\n"
         << "# the first pair, tx ty tz qx qy qz qw) in the first pair's rectified left frame.\n"
         << "trajectory: trajectory.tum\n";
    write_text_file_atomically(directory / "trajectory.tum",
                               tum_trajectory(world_trajectory(world, rig), world.path->rate_hz));
  }
  write_text_file_atomically(directory / "truth.yaml", yaml.str());
}

std::string tum_line(double seconds, const calib::RigidMotion& pose) {
  std::ostringstream out;
  out.precision(9);
  const Eigen::Quaterniond q(pose.rotation);
  const Eigen::Vector3d& t = pose.translation;
  out << std::fixed << seconds << std::defaultfloat << ' ' << t.x() << ' ' << t.y() << ' ' << t.z()
      << ' ' << q.x() << ' ' << q.y() << ' ' << q.z() << ' ' << q.w() << '\n';
  return out.str();
}

std::string tum_trajectory(std::span<const calib::RigidMotion> poses, double rate_hz) {
  std::string text;
  for (std::size_t i = 0; i < poses.size(); ++i) {
    text += tum_line(static_cast<double>(i) / rate_hz, poses[i]);
  }
  return text;
}

}  // namespace epipole::hal
