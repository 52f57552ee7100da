#pragma once

#include <array>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

namespace YAML {
class Node;
}

namespace epipole::yaml {
class Fields;
}

namespace epipole::hal {

// A world the simulated cameras render (a scene's `world:`, docs/boards.md; rendered and its
// truth computed by world_scene.hpp). The world frame: origin on the floor directly below the
// left camera's centre (at the board file's pose), X right, Y up, Z forward (horizontal). The
// floor is the plane Y = 0, the wall the plane Z = distance_m, boxes stand on the floor,
// axis-aligned. Lengths in metres.

// Where the rig stands and how it looks. The board file gives height and angles; the position
// over the floor and the heading are for moving rigs (a rendered trajectory).
struct RigPose {
  double height_m = 0.5;  // the left camera's optical centre above the floor
  double pitch_deg = 0;   // looking down: positive
  double roll_deg = 0;    // the image's right side lower (clockwise seen from behind): positive
  double x_m = 0;         // the left camera's centre over the floor (world X and Z)
  double z_m = 0;
  double yaw_deg = 0;  // turned towards +X (to the right): positive

  friend bool operator==(const RigPose&, const RigPose&) = default;
};

// A photo on a surface, tiled with mirrored repeat; texel_mm: the size of one of its pixels.
struct WorldTexture {
  std::filesystem::path file;
  double texel_mm = 1;
};

// A vertical wall facing the rig, across the whole view: the plane Z = distance_m.
struct WorldWall {
  double distance_m = 6;
  WorldTexture texture;
};

// A box standing on the floor, its faces parallel to the world's axes.
struct WorldBox {
  double x_m = 0;       // X of its centre
  double z_m = 1;       // Z of its front face (the one nearest the rig)
  double width_m = 1;   // along X
  double height_m = 1;  // along Y
  double depth_m = 1;   // along Z
  WorldTexture texture;
};

// A path the rig follows (the world rendered as a trajectory, one pair per pose): from the first
// waypoint facing the second, straight from each waypoint to the next at speed_mps, turning on
// the spot at each to face the next one at turn_dps (the shorter way); at the end of a closed
// path (the last waypoint the first), it turns to face the second again. Its poses are taken at
// rate_hz, from the start: the board's trigger rate, so that pair i is the pose at i / rate_hz.
// Height, pitch and roll are the world's rig's.
struct WorldPath {
  std::vector<std::array<double, 2>> waypoints_m;  // X, Z over the floor; at least 2
  double speed_mps = 1;
  double turn_dps = 90;
  double rate_hz = 15;
  std::size_t max_poses = 0;  // 0: the whole path; else its first poses only (a short run)
};

struct SimWorld {
  RigPose rig;
  std::optional<WorldPath> path;  // the rig moves: `frames` is not used
  WorldTexture floor;
  std::optional<WorldWall> wall;
  std::vector<WorldBox> boxes;
  double noise = 1;  // sensor noise, grey levels (standard deviation)
  int frames = 8;    // pairs rendered: one geometry, independent noise
};

// The map `world` at `key` ("sim.scenes.NAME.world") of the board file: every number checked,
// unknown keys refused; Error naming the file and the key. Textures are not read here.
SimWorld read_world(const yaml::Fields& file, const YAML::Node& world, const std::string& key);

// The rig's pose at each pair: along the world's path, or world.frames times world.rig.
std::vector<RigPose> world_poses(const SimWorld& world);

}  // namespace epipole::hal
