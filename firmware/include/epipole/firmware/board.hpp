#pragma once

#include <memory>
#include <string>
#include <vector>

#include "epipole/core/image.hpp"
#include "epipole/firmware/board_config.hpp"
#include "epipole/hal/camera.hpp"
#include "epipole/hal/clock.hpp"
#include "epipole/hal/hardware.hpp"
#include "epipole/hal/recovery.hpp"
#include "epipole/hal/serial_port.hpp"
#include "epipole/hal/stereo_pairing.hpp"
#include "epipole/hal/trigger.hpp"

namespace epipole::firmware {

// Images for the simulated cameras: one list per side, of the board's image size.
struct SceneImages {
  std::vector<GrayImage> left;
  std::vector<GrayImage> right;
};

// The images of the board's simulated scene, read from its files and fitted to the cameras'
// size (hal/sim_scene.hpp), or synthesised. Throws Error naming the file; builds without image
// files (cross builds without libpng/libjpeg) throw saying so.
SceneImages load_scene_images(const BoardConfig& board);
// False in builds without image files, whose simulated board has nothing to replay.
bool can_load_scene_images();

// The hardware of a board — cameras, trigger line, serial link, clock — made from its
// configuration by the HAL (hal::Hardware, through the backend registry), each camera and the
// link wrapped so that they recover from faults by themselves (hal/recovery.hpp). On the
// simulated board everything runs on its virtual clock.
class Board {
 public:
  // The simulated board's images are loaded with load_scene_images().
  explicit Board(const BoardConfig& config);
  // With these images for a simulated board (tests; ignored on other boards).
  Board(const BoardConfig& config, SceneImages sim_images);
  ~Board();
  Board(const Board&) = delete;
  Board& operator=(const Board&) = delete;

  hal::Clock& clock() { return hardware_.clock(); }
  hal::CameraSource& left() { return left_; }
  hal::CameraSource& right() { return right_; }
  hal::RecoveringCamera& left_recovery() { return left_; }
  hal::RecoveringCamera& right_recovery() { return right_; }
  const hal::RecoveringCamera& left_recovery() const { return left_; }
  const hal::RecoveringCamera& right_recovery() const { return right_; }
  hal::TriggerLine* trigger() { return hardware_.trigger(); }
  // Null when the board has no link.
  hal::SerialPort* serial() { return serial_ ? serial_.get() : nullptr; }
  const hal::RecoveringSerialPort* serial_recovery() const { return serial_.get(); }
  // The robot's end of a simulated link ("pty" backend), else empty.
  std::string serial_peer() const;
  // The devices themselves, unwrapped (the simulated scene's size; tests reach the simulation
  // through hal::Hardware::sim()).
  hal::Hardware& hardware() { return hardware_; }
  const hal::Hardware& hardware() const { return hardware_; }

 private:
  hal::Hardware hardware_;
  hal::RecoveringCamera left_, right_;
  std::unique_ptr<hal::RecoveringSerialPort> serial_;
};

}  // namespace epipole::firmware
