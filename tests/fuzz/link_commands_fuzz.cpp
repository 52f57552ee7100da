// libFuzzer target: bytes from the robot through the link into the frame loop's command
// handling on the simulated board. The bytes go to the link's decoder as its thread would give
// them (Link::take_bytes; the board has no port, so the acks reach an observer instead), then
// the loop runs a pair, applying what came. Every command is answered once (those beyond the
// queue and its overflow only counted), nothing throws, and the board's trigger and cameras
// keep settings they accept. The heavy stages start off (a command may turn them on).
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <span>

#include "epipole/core/error.hpp"
#include "epipole/firmware/firmware.hpp"
#include "fuzz_file.hpp"
#include "sim/sim.hpp"
#include "sim/sim_scene.hpp"
#include "sim/sim_settings.hpp"

namespace {

using namespace epipole;

constexpr const char* kBoard =
    "version: 1\nname: fuzz\n"
    "cameras: {backend: sim, left: left, right: right, width: 64, height: 48, trigger: external,"
    " timeout_ms: 200}\n"
    "trigger: {backend: sim, line: sim, rate_hz: 30}\n"
    "serial: {backend: none}\n"
    "stereo: {max_disparity: 16}\n"
    "threads: {count: 1}\n"
    "stages: {disparity: false, sparse: false, detect: false}\n"
    "sim: {scenes: {fuzz: {synthesize: unused.png, disparity: 4}}}\n";

struct Acks final : firmware::FrameObserver {
  std::uint64_t count = 0;
  void on_frame(const firmware::FrameResult&) override {}
  void on_message(const protocol::Message& m) override {
    if (std::holds_alternative<protocol::CommandAck>(m)) ++count;
  }
};

std::shared_ptr<const hal::StereoImages> images() {
  auto s = std::make_shared<hal::StereoImages>();
  GrayImage left(64, 48);
  for (int y = 0; y < 48; ++y) {
    for (int x = 0; x < 64; ++x) {
      left.view().row(y)[x] = static_cast<std::uint8_t>((x * 37 + y * 91 + x * y) % 251);
    }
  }
  s->right.push_back(hal::synthesize_right(left.view(), 4));
  s->left.push_back(std::move(left));
  return s;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const firmware::BoardConfig config = [] {
    firmware::BoardConfig c = firmware::parse_board_config(kBoard, fuzz::folder() / "board.yaml");
    hal::sim_settings(c.sections).images = images();
    return c;
  }();
  firmware::Firmware fw(config);
  Acks acks;
  fw.frame_loop().set_observer(&acks);
  fw.link().take_bytes(std::as_bytes(std::span(data, size)));
  const firmware::LinkCounters before = fw.link().counters();
  const std::atomic<bool> stop{false};
  const firmware::RunSummary s = fw.run(1, stop);
  // Up to 16 commands wait in the queue and 16 more are answered busy; the rest are counted.
  const std::uint64_t answerable = std::min<std::uint64_t>(before.commands, 32);
  if (acks.count != s.commands || s.commands != answerable) std::abort();
  hal::validate(fw.board().trigger()->config());  // throws (and the fuzzer reports) if broken
  for (const hal::Side side : {hal::Side::left, hal::Side::right}) {
    const hal::CameraConfig& camera =
        hal::simulated_board(fw.board().hardware())->camera(side)->config();
    hal::validate_exposure(camera.device, camera.exposure, camera.gain);
  }
  return 0;
}
