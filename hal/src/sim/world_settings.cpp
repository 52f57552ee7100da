// A scene's `world:` in the board file (world_settings.hpp): read and checked in every build;
// rendering it is world_scene.cpp's (builds with image files).
#include "sim/world_settings.hpp"

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cmath>

#include "epipole/core/angles.hpp"
#include "epipole/core/error.hpp"
#include "epipole/core/yaml_fields.hpp"

namespace epipole::hal {

namespace {

constexpr double kWorldMaxMetres = 1000;  // sizes, distances and positions
constexpr int kWorldMaxPathPoses = 2000;  // pairs rendered along a path

// A size or a distance: > 0, at most kWorldMaxMetres.
double world_length(const yaml::Fields& f, const YAML::Node& node, const std::string& key) {
  const double v = f.number(node, key);
  if (v <= 0 || v > kWorldMaxMetres) {
    f.fail(key, cat(v, " is outside (0, ", kWorldMaxMetres, "]: it must be > 0"));
  }
  return v;
}

// `count` numbers, each within -kWorldMaxMetres..kWorldMaxMetres (positions) or, when
// `lengths`, a length.
std::vector<double> world_numbers(const yaml::Fields& f, const YAML::Node& node,
                                  const std::string& key, std::size_t count, bool lengths,
                                  const char* meaning) {
  const std::vector<double> values = f.numbers(node, key);
  if (values.size() != count) {
    f.fail(key, cat("expected ", count, " numbers ", meaning, ", found ", values.size()));
  }
  for (std::size_t i = 0; i < values.size(); ++i) {
    const std::string item = cat(key, "[", i, "]");
    if (lengths) {
      world_length(f, node[i], item);
    } else if (values[i] < -kWorldMaxMetres || values[i] > kWorldMaxMetres) {
      f.fail(item, cat(values[i], " is outside ", -kWorldMaxMetres, "..", kWorldMaxMetres));
    }
  }
  return values;
}

// `texture` and `texel_mm` of the map at `key`.
WorldTexture read_world_texture(const yaml::Fields& f, const YAML::Node& map,
                                const std::string& key) {
  WorldTexture t;
  t.file = f.path(f.child(map, key, "texture"), key + ".texture");
  t.texel_mm = f.number_in(f.child(map, key, "texel_mm"), key + ".texel_mm", 0.1, 1000);
  return t;
}

RigPose read_world_rig(const yaml::Fields& f, const YAML::Node& map, const std::string& key) {
  f.only_keys(map, key, {"height_m", "pitch_deg", "roll_deg"});
  RigPose pose;
  pose.height_m = f.number_in(f.child(map, key, "height_m"), key + ".height_m", 0.05, 10);
  f.if_present(map, key, "pitch_deg", [&](const YAML::Node& value, const std::string& k) {
    pose.pitch_deg = f.number_in(value, k, -80, 80);
  });
  f.if_present(map, key, "roll_deg", [&](const YAML::Node& value, const std::string& k) {
    pose.roll_deg = f.number_in(value, k, -60, 60);
  });
  return pose;
}

WorldBox read_world_box(const yaml::Fields& f, const YAML::Node& map, const std::string& key) {
  f.only_keys(map, key, {"at_m", "size_m", "texture", "texel_mm"});
  WorldBox box;
  const std::vector<double> at = world_numbers(f, f.child(map, key, "at_m"), key + ".at_m", 2,
                                               false, "[X of the centre, Z of the front face]");
  box.x_m = at[0];
  box.z_m = at[1];
  const std::vector<double> size = world_numbers(f, f.child(map, key, "size_m"), key + ".size_m", 3,
                                                 true, "[width (X), height (Y), depth (Z)]");
  box.width_m = size[0];
  box.height_m = size[1];
  box.depth_m = size[2];
  box.texture = read_world_texture(f, map, key);
  return box;
}

WorldPath read_world_path(const yaml::Fields& f, const YAML::Node& map, const std::string& key) {
  f.only_keys(map, key, {"waypoints_m", "speed_mps", "turn_dps", "rate_hz"});
  WorldPath path;
  const std::string points_key = key + ".waypoints_m";
  const YAML::Node points = f.child(map, key, "waypoints_m");
  if (!points.IsSequence() || points.size() < 2 || points.size() > 1000) {
    f.fail(points_key, "expected a list of 2 to 1000 waypoints, each [X, Z]");
  }
  for (std::size_t i = 0; i < points.size(); ++i) {
    const std::vector<double> xz =
        world_numbers(f, points[i], cat(points_key, "[", i, "]"), 2, false, "[X, Z]");
    if (i > 0 && xz[0] == path.waypoints_m.back()[0] && xz[1] == path.waypoints_m.back()[1]) {
      f.fail(cat(points_key, "[", i, "]"), "is the waypoint before it again");
    }
    path.waypoints_m.push_back({xz[0], xz[1]});
  }
  path.speed_mps = f.number_in(f.child(map, key, "speed_mps"), key + ".speed_mps", 0.01, 100);
  f.if_present(map, key, "turn_dps", [&](const YAML::Node& value, const std::string& k) {
    path.turn_dps = f.number_in(value, k, 1, 3600);
  });
  path.rate_hz = f.number_in(f.child(map, key, "rate_hz"), key + ".rate_hz", 1, 1000);
  // The poses are rendered and held: a bound on how many.
  const double seconds = [&] {
    double s = 0;
    for (std::size_t i = 1; i < path.waypoints_m.size(); ++i) {
      s += std::hypot(path.waypoints_m[i][0] - path.waypoints_m[i - 1][0],
                      path.waypoints_m[i][1] - path.waypoints_m[i - 1][1]) /
           path.speed_mps;
      s += 180.0 / path.turn_dps;  // at most half a turn at each waypoint
    }
    return s;
  }();
  if (seconds * path.rate_hz + 1 > kWorldMaxPathPoses) {
    f.fail(key, cat("takes up to ", std::llround(seconds * path.rate_hz) + 1,
                    " poses at rate_hz; at most ", kWorldMaxPathPoses, " are rendered"));
  }
  return path;
}

}  // namespace

SimWorld read_world(const yaml::Fields& f, const YAML::Node& map, const std::string& key) {
  f.only_keys(map, key, {"rig", "floor", "wall", "boxes", "noise", "frames", "path"});
  SimWorld world;
  world.rig = read_world_rig(f, f.child(map, key, "rig"), key + ".rig");

  const std::string floor_key = key + ".floor";
  const YAML::Node floor_map = f.child(map, key, "floor");
  f.only_keys(floor_map, floor_key, {"texture", "texel_mm"});
  world.floor = read_world_texture(f, floor_map, floor_key);

  f.if_present(map, key, "wall", [&](const YAML::Node& node, const std::string& k) {
    f.only_keys(node, k, {"distance_m", "texture", "texel_mm"});
    WorldWall wall;
    wall.distance_m = world_length(f, f.child(node, k, "distance_m"), k + ".distance_m");
    wall.texture = read_world_texture(f, node, k);
    world.wall = wall;
  });
  f.if_present(map, key, "boxes", [&](const YAML::Node& node, const std::string& k) {
    if (!node.IsSequence()) {
      f.fail(k, "expected a list of boxes, each {at_m, size_m, texture, texel_mm}");
    }
    for (std::size_t i = 0; i < node.size(); ++i) {
      world.boxes.push_back(read_world_box(f, node[i], cat(k, "[", i, "]")));
    }
  });
  f.if_present(map, key, "noise", [&](const YAML::Node& node, const std::string& k) {
    world.noise = f.number_in(node, k, 0, 50);
  });
  f.if_present(map, key, "frames", [&](const YAML::Node& node, const std::string& k) {
    world.frames = f.integer_in(node, k, 1, 64);
  });
  f.if_present(map, key, "path", [&](const YAML::Node& node, const std::string& k) {
    world.path = read_world_path(f, node, k);
  });
  return world;
}

std::vector<RigPose> world_poses(const SimWorld& world) {
  if (!world.path) return std::vector<RigPose>(static_cast<std::size_t>(world.frames), world.rig);
  const WorldPath& path = *world.path;
  const auto& w = path.waypoints_m;
  const auto heading_deg = [&](std::size_t from) {  // of the leg from waypoint `from`
    return degrees(std::atan2(w[from + 1][0] - w[from][0], w[from + 1][1] - w[from][1]));
  };
  // The path as legs of constant motion: a move to a waypoint or a turn to a heading.
  struct Leg {
    double seconds;
    RigPose from;
    double dx, dz, dyaw;  // over the whole leg
  };
  std::vector<Leg> legs;
  RigPose at = world.rig;
  at.x_m = w[0][0];
  at.z_m = w[0][1];
  at.yaw_deg = heading_deg(0);
  const auto turn_to = [&](double yaw_deg) {
    const double turn = std::remainder(yaw_deg - at.yaw_deg, 360.0);
    if (turn == 0) return;
    legs.push_back({std::abs(turn) / path.turn_dps, at, 0, 0, turn});
    at.yaw_deg += turn;
  };
  const bool closed = w.size() > 2 && w.front() == w.back();
  for (std::size_t i = 0; i + 1 < w.size(); ++i) {
    if (i > 0) turn_to(heading_deg(i));
    const double dx = w[i + 1][0] - w[i][0], dz = w[i + 1][1] - w[i][1];
    legs.push_back({std::hypot(dx, dz) / path.speed_mps, at, dx, dz, 0});
    at.x_m = w[i + 1][0];
    at.z_m = w[i + 1][1];
  }
  if (closed) turn_to(heading_deg(0));
  double total = 0;
  for (const Leg& leg : legs) total += leg.seconds;
  std::vector<RigPose> poses;
  std::size_t leg = 0;
  double leg_start = 0;
  for (int i = 0;; ++i) {
    const double t = i / path.rate_hz;
    if (t > total + 1e-9) break;
    while (leg + 1 < legs.size() && t > leg_start + legs[leg].seconds) {
      leg_start += legs[leg].seconds;
      ++leg;
    }
    const Leg& l = legs[leg];
    const double a = std::clamp((t - leg_start) / l.seconds, 0.0, 1.0);
    RigPose p = l.from;
    p.x_m += a * l.dx;
    p.z_m += a * l.dz;
    p.yaw_deg += a * l.dyaw;
    poses.push_back(p);
    if (poses.size() == path.max_poses) break;
  }
  return poses;
}

}  // namespace epipole::hal
