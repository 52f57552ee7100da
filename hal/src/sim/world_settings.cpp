// A scene's `world:` in the board file (world_settings.hpp): read and checked in every build;
// rendering it is world_scene.cpp's (builds with image files).
#include "sim/world_settings.hpp"

#include <yaml-cpp/yaml.h>

#include "epipole/core/error.hpp"
#include "epipole/core/yaml_fields.hpp"

namespace epipole::hal {

namespace {

constexpr double kWorldMaxMetres = 1000;  // sizes, distances and positions

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

}  // namespace

SimWorld read_world(const yaml::Fields& f, const YAML::Node& map, const std::string& key) {
  f.only_keys(map, key, {"rig", "floor", "wall", "boxes", "noise", "frames"});
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
  return world;
}

}  // namespace epipole::hal
