#pragma once

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

struct SimWorld {
  RigPose rig;
  WorldTexture floor;
  std::optional<WorldWall> wall;
  std::vector<WorldBox> boxes;
  double noise = 1;  // sensor noise, grey levels (standard deviation)
  int frames = 8;    // pairs rendered: one geometry, independent noise
};

// The map `world` at `key` ("sim.scenes.NAME.world") of the board file: every number checked,
// unknown keys refused; Error naming the file and the key. Textures are not read here.
SimWorld read_world(const yaml::Fields& file, const YAML::Node& world, const std::string& key);

}  // namespace epipole::hal
