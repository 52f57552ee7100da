#pragma once

#include <cstdint>
#include <filesystem>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "epipole/core/settings_sections.hpp"
#include "epipole/firmware/protocol/stages.hpp"
#include "epipole/hal/backend_settings.hpp"
#include "epipole/hal/camera.hpp"
#include "epipole/hal/serial_port.hpp"
#include "epipole/hal/stereo_pairing.hpp"
#include "epipole/hal/trigger.hpp"
#include "epipole/vision/stereo.hpp"

namespace epipole::firmware {

// A stage's own section of the board file (the top-level key of the stage's name), as the stage
// read it (stages::StageDefinition::read_settings); opaque to everyone else.
class StageSettings {
 public:
  virtual ~StageSettings() = default;
  virtual std::unique_ptr<StageSettings> clone() const = 0;
};
using StageSections = SettingsSections<StageSettings>;

// An output's own subsection of the board file's `outputs` (outputs: {<name>: {...}}), as the
// output read it (outputs::OutputDefinition::read_settings); opaque to everyone else.
class OutputSettings {
 public:
  virtual ~OutputSettings() = default;
  virtual std::unique_ptr<OutputSettings> clone() const = 0;
};
using OutputSections = SettingsSections<OutputSettings>;

// A board's configuration file (board.yaml, docs/boards.md): which backends and devices the
// board has, the image size and every stage's limits. The firmware sizes all of its memory from
// it at start-up. Loading either returns a complete, validated configuration or throws Error
// naming the file and the key.
struct BoardConfig {
  static constexpr int kVersion = 1;

  std::string name;                 // "sim", "raspberrypi5-ov9281", ...
  std::filesystem::path directory;  // the folder of the file: relative paths start here

  struct Cameras {
    std::string backend;     // a camera backend of the HAL's registry (docs/boards.md)
    hal::CameraConfig left;  // device, size, format, rate, exposure, gain, trigger mode
    hal::CameraConfig right;
    hal::Nanoseconds timeout = 200'000'000;  // acquire timeout before a camera counts as late
  } cameras;

  struct Trigger {
    std::string backend;  // a trigger backend of the registry, or none (free-running cameras)
    hal::TriggerConfig line;
  } trigger;

  hal::PairingConfig pairing;
  // Frame timestamp minus trigger edge on this board (pairing.edge_delay_us); when known, every
  // pair is checked against the trigger's own edge of its sequence.
  std::optional<hal::Nanoseconds> pairing_edge_delay;

  enum class LinkProtocol { epipole, mavlink };
  struct Serial {
    std::string backend = "pty";  // termios | pty | none
    hal::SerialConfig port;
    LinkProtocol protocol = LinkProtocol::epipole;
    std::uint8_t mavlink_system_id = 1;
    std::uint8_t mavlink_component_id = 196;  // MAV_COMP_ID_OBSTACLE_AVOIDANCE
  } serial;

  std::filesystem::path calibration;  // absolute after loading; empty: images are rectified

  // The stages that run (a bit per protocol::Stage): the always-on ones and those the board
  // file's `stages` leaves on (all of them unless it says otherwise).
  protocol::StageMask stages = protocol::kAllStages;

  enum class CornerDetector { fast, harris };
  struct Corners {
    CornerDetector detector = CornerDetector::fast;
    int threshold = 20;      // FAST threshold
    int max_corners = 2000;  // per image, the strongest kept
    int grid = 4;            // bucketing: grid x grid cells share max_corners
  } corners;

  vision::StereoConfig stereo;  // width and height come from the cameras

  struct Sparse {
    int max_points = 48;     // 3-D points sent per frame (the protocol's limit), best matches first
    int row_tolerance = 1;   // pixels: candidates on rows y - t .. y + t
    int ratio = 80;          // percent: best distance below this share of the second best
    int max_distance = 64;   // Hamming distance of the 256-bit descriptors
    int max_matches = 2000;  // matches kept per frame
  } sparse;

  // How well the calibration still holds (docs/calibration.md, "The drift"): the corners matched
  // again on rows +- band_rows, their rows measured to a fraction of a pixel, the right camera's
  // turn estimated over window_pairs pairs.
  struct CalibrationHealth {
    int band_rows = 8;
    int window_pairs = 30;
    // Correcting the drift while running (docs/calibration.md, "Correcting the drift"): when the
    // window's rows are off by at least min_offset_px and undoing the estimated turn lowers
    // them, the right camera's map is rebuilt with it, up to max_correction_deg from the file.
    bool online_correction = false;
    double max_correction_deg = 1.0;
    double min_offset_px = 0.05;
  } calibration_health;

  struct Detector {
    std::filesystem::path cascade;  // compiled cascade (.bin); empty: no detection
    double scale_factor = 1.1;
    int min_neighbors = 3;
    int min_size = 30;
    int max_size = 0;  // 0: the image size
  } detector;

  struct Obstacles {
    int sectors = 72;
    double band_top = 0.25;  // rows of the image searched, as fractions of its height
    double band_bottom = 0.75;
    double min_depth_m = 0.2;
    double max_depth_m = 20.0;
    int min_confidence = 0;  // 1..255: pixels the disparity trusts less are left out; 0 off
  } obstacles;

  // The nearest depth in a grid of cells over the whole view, sent with each pair (0 x 0: off).
  struct DepthGrid {
    int columns = 0;
    int rows = 0;
    double min_depth_m = 0.2;
    double max_depth_m = 20.0;
    int min_confidence = 0;  // as the obstacles'
  } depth_grid;

  struct Threads {
    // The vision stages' pool (and the disparity's row stripes). Not given: the CPUs the
    // firmware may run on (affinity's, else the process's).
    int count = 1;
    std::vector<int> affinity;  // CPUs for the frame loop and its workers; empty: any
    int realtime_priority = 0;  // SCHED_FIFO priority 1..99; 0: normal scheduling
    bool lock_memory = false;   // mlockall after start-up
    // The maps thread (a corrected rig's map rebuilt) at SCHED_IDLE, in the time the pairs leave
    // (`maps: idle`), or at the scheduling threads start with (`maps: normal`).
    bool maps_idle = true;
  } threads;

  std::optional<std::size_t> memory_budget_bytes;  // start-up fails above it

  std::filesystem::path snapshot_directory;  // where the snapshot command writes; empty: refused
  int snapshot_limit = 200;                  // snapshots the folder may hold (those there count)
  double snapshot_min_free_mb = 64;          // left free on its file system

  // The board file's sections that backends read themselves (the registry's SectionBackend):
  // those present and those the chosen backends need.
  hal::BackendSections sections;
  // The sections of the stages that read their own (every such stage has one, the file's or its
  // defaults).
  StageSections stage_sections;
  // The outputs the file turns on (besides the serial link, which `serial` makes): a subsection
  // of `outputs` each, by the output's name (docs/outputs.md).
  OutputSections outputs;

  int width() const { return cameras.left.width; }
  int height() const { return cameras.left.height; }
  // What the HAL's registry says of the board's backends.
  bool has_trigger() const;  // trigger.backend is not "none" (else free-running cameras)
  bool has_link() const;     // serial.backend is not "none"
  // The period frames come at as the file sets it: the trigger's, or free running the faster
  // camera's.
  hal::Nanoseconds frame_period() const;
};

// Reads and validates a board file; `path` is the file or its folder (then board.yaml in it).
// ${NAME} in paths is replaced by the environment variable NAME; ${EPIPOLE_DATA_DIR} defaults to
// the data cache of scripts/fetch-data.sh. Relative paths are relative to the file's folder.
BoardConfig load_board_config(const std::filesystem::path& path);
// The same with some keys set first, each override `KEY=VALUE`: KEY a dotted path of map keys
// (`stereo.method`), added when the file has no such key; VALUE read as YAML (`bm`, `[0.2, 0.8]`).
// The result is validated as a file is. Throws Error naming an override that does not apply.
// `camera_options` go to the section of the cameras' backend (epipole-fw --scene), which checks
// them; a backend without a section takes none.
BoardConfig load_board_config(const std::filesystem::path& path,
                              std::span<const std::string> overrides,
                              std::span<const hal::BackendOption> camera_options = {});
BoardConfig parse_board_config(const std::string& yaml, const std::filesystem::path& file,
                               std::span<const hal::BackendOption> camera_options = {});

// Cross-checks a configuration (also done by the loaders): stage limits against the image size,
// the pairing tolerance against the trigger period, the trigger period and the exposure against
// the cameras' timeout (frame_timing_problem). Throws Error naming the file and the key.
void validate(const BoardConfig& config, const std::string& file);

// Why the cameras could not follow a frame `period` (the trigger's; free running, the cameras')
// with an `exposure` (0: automatic) within `camera_timeout`, or empty when they can: each frame
// must come within the timeout of the one before (period + exposure below it), or the cameras
// time out and are reopened again and again; and a camera cannot expose longer than the period.
std::string frame_timing_problem(hal::Nanoseconds period, hal::Nanoseconds exposure,
                                 hal::Nanoseconds camera_timeout);

// Why the service manager's watchdog (interval; 0: none) could fire while the frame loop waits
// for a late pair, or empty: the loop pings it after every pair and every wait of up to the
// cameras' timeout, a ping is sent at most every half interval, so the timeout may be at most a
// quarter of it (the other quarter for the processing after the wait).
std::string watchdog_problem(const BoardConfig& config, hal::Nanoseconds watchdog_interval);

}  // namespace epipole::firmware
