#include "epipole/hal/hardware.hpp"

#include <utility>

#include "epipole/core/error.hpp"

namespace epipole::hal {

namespace {

// What the devices of the cameras' backend share, made from its section of the board file.
std::unique_ptr<BackendBoard> make_backend_board(const HardwareConfig& config,
                                                 const BackendRegistry& registry) {
  const char* name = registry.camera_traits(config.camera_backend).section;
  if (name == nullptr) return nullptr;
  const SectionBackend* section = registry.section(name);
  const BackendSettings* settings = config.sections.find(name);
  require(section != nullptr && settings != nullptr, "cameras: backend '", config.camera_backend,
          "' needs the board file's '", name, "' section");
  return section->make_board(*settings, config);
}

}  // namespace

Hardware::Hardware(HardwareConfig config, const BackendRegistry& registry)
    : board_(make_backend_board(config, registry)) {
  if (board_ != nullptr && board_->own_clock() != nullptr) clock_ = board_->own_clock();
  BackendContext context;
  context.clock = clock_;
  context.board = board_.get();
  cameras_[index(Side::left)] = registry.create_camera(config.camera_backend, config.left, context);
  cameras_[index(Side::right)] =
      registry.create_camera(config.camera_backend, config.right, context);
  if (config.trigger_backend != kNoBackend) {
    trigger_ = registry.create_trigger(config.trigger_backend, config.trigger, context);
  }
  if (config.serial_backend != kNoBackend) {
    serial_ = registry.create_serial(config.serial_backend, config.serial, context);
  }
}

Hardware::~Hardware() = default;

bool stand_in_for_devices(HardwareConfig& config, const BackendRegistry& registry) {
  if (registry.camera_traits(config.camera_backend).simulated) return false;
  for (const SectionBackend& section : registry.sections()) {
    if (section.stand_in) {
      section.stand_in(config);
      return true;
    }
  }
  throw Error("this build has no backend to stand in for the board's devices");
}

}  // namespace epipole::hal
