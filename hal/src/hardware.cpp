#include "epipole/hal/hardware.hpp"

#include <utility>
#include <vector>

#include "epipole/core/error.hpp"

namespace epipole::hal {

namespace {

// What the devices of a backend with a section share (null: it has none), made once per section
// from the board file's section and kept in `boards`; `part` names the devices in errors.
BackendBoard* shared_board_for(
    const char* part, const std::string& backend, BackendTraits traits,
    const HardwareConfig& config, const BackendRegistry& registry,
    std::vector<std::pair<std::string, std::unique_ptr<BackendBoard>>>& boards) {
  if (traits.section == nullptr) return nullptr;
  for (const auto& [name, board] : boards) {
    if (name == traits.section) return board.get();
  }
  const SectionBackend* section = registry.section(traits.section);
  const BackendSettings* settings = config.sections.find(traits.section);
  require(section != nullptr && settings != nullptr, part, ": backend '", backend,
          "' needs the board file's '", traits.section, "' section");
  std::unique_ptr<BackendBoard> board = section->make_board(*settings, config);
  require(board != nullptr, part, ": backend '", backend, "' made nothing of its '", traits.section,
          "' section");
  boards.emplace_back(traits.section, std::move(board));
  return boards.back().second.get();
}

}  // namespace

// The cameras' backend's board first: its clock, when it has one, is every device's.
Hardware::Hardware(HardwareConfig config, const BackendRegistry& registry) {
  BackendContext context;
  context.board =
      shared_board_for("cameras", config.camera_backend,
                       registry.camera_traits(config.camera_backend), config, registry, boards_);
  cameras_board_ = context.board;
  if (cameras_board_ != nullptr && cameras_board_->own_clock() != nullptr) {
    clock_ = cameras_board_->own_clock();
  }
  context.clock = clock_;
  cameras_[index(Side::left)] = registry.create_camera(config.camera_backend, config.left, context);
  cameras_[index(Side::right)] =
      registry.create_camera(config.camera_backend, config.right, context);
  if (config.trigger_backend != kNoBackend) {
    context.board = shared_board_for("trigger", config.trigger_backend,
                                     registry.trigger_traits(config.trigger_backend), config,
                                     registry, boards_);
    require_cameras_clock("trigger", config.trigger_backend, context.board);
    trigger_ = registry.create_trigger(config.trigger_backend, config.trigger, context);
  }
  if (config.serial_backend != kNoBackend) {
    context.board =
        shared_board_for("serial", config.serial_backend,
                         registry.serial_traits(config.serial_backend), config, registry, boards_);
    require_cameras_clock("serial", config.serial_backend, context.board);
    serial_ = registry.create_serial(config.serial_backend, config.serial, context);
  }
}

// Only the cameras' backend sets the board's clock: devices of another backend on a clock of
// their own would time edges the cameras cannot be paired with (a simulated trigger beside real
// cameras).
void Hardware::require_cameras_clock(const char* part, const std::string& backend,
                                     BackendBoard* board) const {
  require(board == nullptr || board == cameras_board_ || board->own_clock() == nullptr, part,
          ": backend '", backend,
          "' runs on a clock of its own: the cameras must be of a backend that shares it");
}

std::size_t Hardware::backend_bytes() const {
  std::size_t bytes = 0;
  for (const auto& board : boards_) bytes += board.second->memory_bytes();
  return bytes;
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
