#include "epipole/firmware/board_config.hpp"

#include <cmath>
#include <cstdlib>

#include <algorithm>
#include <set>

#include "config/output_sections.hpp"
#include "config/stage_sections.hpp"
#include "epipole/core/error.hpp"
#include "epipole/core/text_file.hpp"
#include "epipole/core/thread_pool.hpp"
#include "epipole/core/yaml_fields.hpp"
#include "epipole/firmware/link_budget.hpp"
#include "epipole/firmware/protocol/messages.hpp"
#include "epipole/hal/registry.hpp"
#include "output_files.hpp"
#include "stages/stage_table.hpp"

namespace epipole::firmware {

namespace fs = std::filesystem;

hal::Nanoseconds BoardConfig::frame_period() const {
  if (has_trigger()) return pairing.trigger_period;
  return hal::period_of(std::max({cameras.left.fps, cameras.right.fps, 1e-3}));
}

bool BoardConfig::has_trigger() const {
  return trigger.backend != hal::kNoBackend;
}
bool BoardConfig::has_link() const {
  return serial.backend != hal::kNoBackend;
}

namespace {

// Reads one board file: every key known, every value checked, errors naming file and key.
class BoardReader {
 public:
  BoardReader(const fs::path& file, std::span<const hal::BackendOption> camera_options)
      : file_(file), f_(file.string()), camera_options_(camera_options) {}

  BoardConfig read(const std::string& text) {
    const YAML::Node root = f_.parse(text);
    f_.require_map(root, "");
    only_known_keys(root);
    const int version = f_.integer(f_.child(root, "", "version"), "version");
    if (version < 1 || version > BoardConfig::kVersion) {
      f_.fail("version", cat(version, " is not a board file version this firmware reads (1..",
                             BoardConfig::kVersion, ")"));
    }
    BoardConfig c;
    c.directory = file_.parent_path();
    c.name = f_.text(f_.child(root, "", "name"), "name");
    read_cameras(root, c);
    read_trigger(root, c);
    read_pairing(root, c);
    read_serial(root, c);
    if (const YAML::Node n = f_.optional_child(root, "", "calibration"); n.IsDefined()) {
      c.calibration = f_.path(n, "calibration");
    }
    read_stages(root, c);
    read_corners(root, c);
    read_stereo(root, c);
    read_sparse(root, c);
    read_calibration_health(root, c);
    read_detector(root, c);
    read_obstacles(root, c);
    read_depth_grid(root, c);
    read_threads(root, c);
    if (const YAML::Node n = f_.optional_child(root, "", "memory_budget_mb"); n.IsDefined()) {
      const double mb = f_.number(n, "memory_budget_mb");
      if (mb <= 0 || mb > 65536) f_.fail("memory_budget_mb", "must be in (0, 65536]");
      c.memory_budget_bytes = static_cast<std::size_t>(mb * 1024 * 1024);
    }
    if (const YAML::Node n = f_.optional_child(root, "", "snapshot_directory"); n.IsDefined()) {
      c.snapshot_directory = f_.path(n, "snapshot_directory");
    }
    integer(root, "", "snapshot_limit", c.snapshot_limit, 1, 1'000'000);
    number(root, "", "snapshot_min_free_mb", c.snapshot_min_free_mb, 0, 1e7);
    read_backend_sections(root, c);
    stages::read_stage_sections(stages::kPipelineStages, root, f_, c.stage_sections);
    outputs::read_output_sections(outputs::kOutputFiles, root, f_, c.outputs);
    return c;
  }

 private:
  // A map at `key` of the top level, or an undefined node; unknown keys in it are errors.
  YAML::Node section(const YAML::Node& root, const char* key,
                     std::initializer_list<const char*> known) {
    const YAML::Node n = f_.optional_child(root, "", key);
    if (n.IsDefined()) f_.only_keys(n, key, known);
    return n;
  }
  template <typename T, typename Read>
  void optional(const YAML::Node& map, const std::string& path, const char* key, T& out,
                Read read) {
    if (!map.IsDefined()) return;
    f_.if_present(map, path, key,
                  [&](const YAML::Node& n, const std::string& k) { out = read(n, k); });
  }
  void integer(const YAML::Node& map, const std::string& path, const char* key, int& out, int lo,
               int hi) {
    optional(map, path, key, out, [&](const YAML::Node& n, const std::string& k) {
      return f_.integer_in(n, k, lo, hi);
    });
  }
  void number(const YAML::Node& map, const std::string& path, const char* key, double& out,
              double lo, double hi) {
    optional(map, path, key, out,
             [&](const YAML::Node& n, const std::string& k) { return f_.number_in(n, k, lo, hi); });
  }
  void boolean(const YAML::Node& map, const std::string& path, const char* key, bool& out) {
    optional(map, path, key, out,
             [&](const YAML::Node& n, const std::string& k) { return f_.boolean(n, k); });
  }
  void text(const YAML::Node& map, const std::string& path, const char* key, std::string& out) {
    optional(map, path, key, out,
             [&](const YAML::Node& n, const std::string& k) { return f_.text(n, k); });
  }
  // One of `names`; returns its index.
  template <typename E>
  void choice(const YAML::Node& map, const std::string& path, const char* key, E& out,
              std::initializer_list<const char*> names) {
    optional(map, path, key, out, [&](const YAML::Node& n, const std::string& k) {
      const std::string v = f_.text(n, k);
      int i = 0;
      std::string list;
      for (const char* name : names) {
        if (v == name) return static_cast<E>(i);
        list += (i++ == 0 ? "" : ", ") + std::string(name);
      }
      f_.fail(k, cat("'", v, "' is not one of ", list));
    });
  }

  void read_camera(const YAML::Node& cams, const char* side, hal::CameraConfig& camera) {
    const std::string p = cat("cameras.", side);
    const YAML::Node n = f_.child(cams, "cameras", side);
    if (n.IsScalar()) {
      camera.device = f_.text(n, p);
      return;
    }
    f_.only_keys(n, p, {"device"});
    camera.device = f_.text(f_.child(n, p, "device"), p + ".device");
  }
  void read_cameras(const YAML::Node& root, BoardConfig& c) {
    const YAML::Node n = f_.child(root, "", "cameras");
    f_.only_keys(n, "cameras",
                 {"backend", "left", "right", "width", "height", "format", "fps", "exposure_us",
                  "gain", "trigger", "buffers", "timeout_ms"});
    hal::CameraConfig common;
    common.width = f_.integer(f_.child(n, "cameras", "width"), "cameras.width");
    common.height = f_.integer(f_.child(n, "cameras", "height"), "cameras.height");
    c.cameras.backend = f_.text(f_.child(n, "cameras", "backend"), "cameras.backend");
    optional(n, "cameras", "format", common.format, [&](const YAML::Node& v, const std::string& k) {
      const std::string s = f_.text(v, k);
      const auto format = hal::parse_pixel_format(s);
      if (!format) f_.fail(k, cat("'", s, "' is not one of grey, y10, y16, yuyv, nv12, yu12"));
      return *format;
    });
    number(n, "cameras", "fps", common.fps, 0.001, 1000);
    double exposure_us = 0;
    number(n, "cameras", "exposure_us", exposure_us, 0, 10e6);
    common.exposure = static_cast<hal::Nanoseconds>(exposure_us * 1000);
    number(n, "cameras", "gain", common.gain, 0, 1000);
    choice(n, "cameras", "trigger", common.trigger, {"free_running", "external"});
    integer(n, "cameras", "buffers", common.buffer_count, 2, 32);
    int timeout_ms = 200;
    integer(n, "cameras", "timeout_ms", timeout_ms, 1, 60'000);
    c.cameras.timeout = static_cast<hal::Nanoseconds>(timeout_ms) * 1'000'000;
    c.cameras.left = common;
    c.cameras.right = common;
    read_camera(n, "left", c.cameras.left);
    read_camera(n, "right", c.cameras.right);
    for (const hal::CameraConfig* cam : {&c.cameras.left, &c.cameras.right}) {
      try {
        hal::validate(*cam);
      } catch (const Error& e) {
        f_.fail("cameras", e.what());
      }
    }
  }

  void read_trigger(const YAML::Node& root, BoardConfig& c) {
    const YAML::Node n =
        section(root, "trigger", {"backend", "line", "chip", "role", "rate_hz", "pulse_width_us"});
    c.trigger.backend = f_.text(f_.child(n, "trigger", "backend"), "trigger.backend");
    hal::TriggerConfig& t = c.trigger.line;
    text(n, "trigger", "line", t.line);
    text(n, "trigger", "chip", t.chip);
    choice(n, "trigger", "role", t.role, {"master", "slave"});
    number(n, "trigger", "rate_hz", t.rate_hz, 0.001, 1000);
    double width_us = 1000;
    number(n, "trigger", "pulse_width_us", width_us, 1, 1e6);
    t.pulse_width = static_cast<hal::Nanoseconds>(width_us * 1000);
    if (c.has_trigger()) {
      try {
        hal::validate(t);
      } catch (const Error& e) {
        f_.fail("trigger", e.what());
      }
      c.pairing.trigger_period = static_cast<hal::Nanoseconds>(std::llround(1e9 / t.rate_hz));
    }
  }

  void read_pairing(const YAML::Node& root, BoardConfig& c) {
    const YAML::Node n =
        section(root, "pairing", {"tolerance_us", "edge_delay_us", "edge_tolerance_us"});
    double tolerance_us = 2000;
    number(n, "pairing", "tolerance_us", tolerance_us, 1, 1e6);
    c.pairing.tolerance = static_cast<hal::Nanoseconds>(tolerance_us * 1000);
    if (n.IsDefined()) {
      if (const YAML::Node d = f_.optional_child(n, "pairing", "edge_delay_us"); d.IsDefined()) {
        const double us = f_.number(d, "pairing.edge_delay_us");
        if (us < -1e6 || us > 1e6) f_.fail("pairing.edge_delay_us", "must be within +-1 s");
        c.pairing_edge_delay = static_cast<hal::Nanoseconds>(us * 1000);
      }
    }
    double edge_tolerance_us = 2000;
    number(n, "pairing", "edge_tolerance_us", edge_tolerance_us, 1, 1e6);
    c.pairing.edge_tolerance = static_cast<hal::Nanoseconds>(edge_tolerance_us * 1000);
  }

  void read_serial(const YAML::Node& root, BoardConfig& c) {
    const YAML::Node n =
        section(root, "serial", {"backend", "device", "baud", "protocol", "mavlink"});
    text(n, "serial", "backend", c.serial.backend);
    text(n, "serial", "device", c.serial.port.device);
    integer(n, "serial", "baud", c.serial.port.baud, 50, 4'000'000);
    choice(n, "serial", "protocol", c.serial.protocol, {"epipole", "mavlink"});
    if (n.IsDefined()) {
      const YAML::Node m = f_.optional_child(n, "serial", "mavlink");
      if (m.IsDefined()) {
        f_.only_keys(m, "serial.mavlink", {"system_id", "component_id"});
        int system = c.serial.mavlink_system_id;
        int component = c.serial.mavlink_component_id;
        integer(m, "serial.mavlink", "system_id", system, 1, 255);
        integer(m, "serial.mavlink", "component_id", component, 1, 255);
        c.serial.mavlink_system_id = static_cast<std::uint8_t>(system);
        c.serial.mavlink_component_id = static_cast<std::uint8_t>(component);
      }
    }
    const bool device =
        hal::BackendRegistry::builtin().serial_traits(c.serial.backend).needs_device;
    if (device && c.serial.port.device.empty()) {
      f_.fail("serial.device", cat("a ", c.serial.backend, " serial port needs a device"));
    }
    if (device && !hal::is_supported_baud(c.serial.port.baud)) {
      f_.fail("serial.baud", cat(c.serial.port.baud, " is not a baud rate termios supports"));
    }
  }

  void read_stages(const YAML::Node& root, BoardConfig& c) {
    std::vector<std::string_view> keys;
    for (const protocol::StageInfo& s : protocol::kStages) {
      if (s.kind == protocol::StageKind::switchable) keys.push_back(s.name);
    }
    const YAML::Node n = f_.optional_child(root, "", "stages");
    if (n.IsDefined()) f_.only_keys(n, "stages", keys);
    for (const protocol::StageInfo& s : protocol::kStages) {
      if (s.kind != protocol::StageKind::switchable) continue;
      bool on = protocol::has_stage(c.stages, s.id);
      boolean(n, "stages", std::string(s.name).c_str(), on);
      c.stages = static_cast<protocol::StageMask>(on ? c.stages | protocol::stage_bit(s.id)
                                                     : c.stages & ~protocol::stage_bit(s.id));
    }
  }

  void read_corners(const YAML::Node& root, BoardConfig& c) {
    const YAML::Node n = section(root, "corners", {"detector", "threshold", "max_corners", "grid"});
    choice(n, "corners", "detector", c.corners.detector, {"fast", "harris"});
    integer(n, "corners", "threshold", c.corners.threshold, 0, 255);
    integer(n, "corners", "max_corners", c.corners.max_corners, 1, 100'000);
    integer(n, "corners", "grid", c.corners.grid, 1, 64);
  }

  void read_stereo(const YAML::Node& root, BoardConfig& c) {
    const YAML::Node n = section(
        root, "stereo",
        {"method", "max_disparity", "p1", "p2", "block_size", "uniqueness", "lr_max_diff",
         "speckle_size", "speckle_range", "fill_occlusions", "spatial_percent", "spatial_max_step",
         "spatial_passes", "hole_fill", "temporal_percent", "temporal_max_step"});
    vision::StereoConfig& s = c.stereo;
    choice(n, "stereo", "method", s.method, {"sgm", "bm"});
    integer(n, "stereo", "max_disparity", s.max_disparity, 16, 256);
    if (s.max_disparity % 16 != 0) {
      f_.fail("stereo.max_disparity", cat(s.max_disparity, " is not a multiple of 16"));
    }
    integer(n, "stereo", "p1", s.p1, 1, 1000);
    integer(n, "stereo", "p2", s.p2, 1, 4000);
    if (s.p2 < s.p1) f_.fail("stereo.p2", cat(s.p2, " is smaller than p1 ", s.p1));
    integer(n, "stereo", "block_size", s.block_size, 3, 21);
    if (s.block_size % 2 == 0) f_.fail("stereo.block_size", cat(s.block_size, " is not odd"));
    integer(n, "stereo", "uniqueness", s.uniqueness, 0, 99);
    integer(n, "stereo", "lr_max_diff", s.lr_max_diff, -1, 256);
    integer(n, "stereo", "speckle_size", s.speckle_size, 0, 1'000'000);
    integer(n, "stereo", "speckle_range", s.speckle_range, 0, 255);
    boolean(n, "stereo", "fill_occlusions", s.fill_occlusions);
    integer(n, "stereo", "spatial_percent", s.spatial_percent, 0, 99);
    integer(n, "stereo", "spatial_max_step", s.spatial_max_step, 1, 7);
    integer(n, "stereo", "spatial_passes", s.spatial_passes, 1, 4);
    integer(n, "stereo", "hole_fill", s.hole_fill, 0, 65535);
    integer(n, "stereo", "temporal_percent", s.temporal_percent, 0, 99);
    integer(n, "stereo", "temporal_max_step", s.temporal_max_step, 1, 7);
  }

  void read_sparse(const YAML::Node& root, BoardConfig& c) {
    const YAML::Node n = section(
        root, "sparse", {"max_points", "row_tolerance", "ratio", "max_distance", "max_matches"});
    integer(n, "sparse", "max_points", c.sparse.max_points, 0, protocol::kMaxPoints);
    integer(n, "sparse", "row_tolerance", c.sparse.row_tolerance, 0, 16);
    integer(n, "sparse", "ratio", c.sparse.ratio, 1, 100);
    integer(n, "sparse", "max_distance", c.sparse.max_distance, 0, 256);
    integer(n, "sparse", "max_matches", c.sparse.max_matches, 1, 100'000);
  }

  void read_calibration_health(const YAML::Node& root, BoardConfig& c) {
    const YAML::Node n = section(
        root, "calibration_health",
        {"band_rows", "window_pairs", "online_correction", "max_correction_deg", "min_offset_px"});
    BoardConfig::CalibrationHealth& h = c.calibration_health;
    integer(n, "calibration_health", "band_rows", h.band_rows, 1, 64);
    integer(n, "calibration_health", "window_pairs", h.window_pairs, 3, 1000);
    boolean(n, "calibration_health", "online_correction", h.online_correction);
    number(n, "calibration_health", "max_correction_deg", h.max_correction_deg, 0, 5);
    number(n, "calibration_health", "min_offset_px", h.min_offset_px, 0, 10);
    if (c.calibration_health.band_rows < c.sparse.row_tolerance) {
      f_.fail("calibration_health.band_rows",
              cat(c.calibration_health.band_rows, " is narrower than sparse.row_tolerance ",
                  c.sparse.row_tolerance));
    }
  }

  void read_detector(const YAML::Node& root, BoardConfig& c) {
    const YAML::Node n = section(
        root, "detector", {"cascade", "scale_factor", "min_neighbors", "min_size", "max_size"});
    if (n.IsDefined()) {
      if (const YAML::Node p = f_.optional_child(n, "detector", "cascade"); p.IsDefined()) {
        c.detector.cascade = f_.path(p, "detector.cascade");
      }
    }
    number(n, "detector", "scale_factor", c.detector.scale_factor, 1.0001, 4.0);
    integer(n, "detector", "min_neighbors", c.detector.min_neighbors, 0, 100);
    integer(n, "detector", "min_size", c.detector.min_size, 1, 16384);
    integer(n, "detector", "max_size", c.detector.max_size, 0, 16384);
  }

  void read_obstacles(const YAML::Node& root, BoardConfig& c) {
    const YAML::Node n = section(
        root, "obstacles", {"sectors", "band", "min_depth_m", "max_depth_m", "min_confidence"});
    BoardConfig::Obstacles& o = c.obstacles;
    integer(n, "obstacles", "sectors", o.sectors, 1, 72);
    if (n.IsDefined()) {
      if (const YAML::Node b = f_.optional_child(n, "obstacles", "band"); b.IsDefined()) {
        const std::vector<double> band = f_.numbers(b, "obstacles.band");
        if (band.size() != 2 || band[0] < 0 || band[1] > 1 || band[0] >= band[1]) {
          f_.fail("obstacles.band", "expected [top, bottom] with 0 <= top < bottom <= 1");
        }
        o.band_top = band[0];
        o.band_bottom = band[1];
      }
    }
    number(n, "obstacles", "min_depth_m", o.min_depth_m, 0.0, 1000.0);
    // Depths are measured in millimetres held in 16 bits.
    number(n, "obstacles", "max_depth_m", o.max_depth_m, 0.001, 65.5);
    integer(n, "obstacles", "min_confidence", o.min_confidence, 0, 255);
    if (o.max_depth_m <= o.min_depth_m) {
      f_.fail("obstacles.max_depth_m", "must be greater than min_depth_m");
    }
  }

  void read_depth_grid(const YAML::Node& root, BoardConfig& c) {
    const YAML::Node n = section(
        root, "depth_grid", {"columns", "rows", "min_depth_m", "max_depth_m", "min_confidence"});
    BoardConfig::DepthGrid& g = c.depth_grid;
    integer(n, "depth_grid", "columns", g.columns, 0, protocol::kMaxGridCells);
    integer(n, "depth_grid", "rows", g.rows, 0, protocol::kMaxGridCells);
    if ((g.columns == 0) != (g.rows == 0)) {
      f_.fail("depth_grid", "columns and rows are both 0 (no grid) or both at least 1");
    }
    if (g.columns * g.rows > protocol::kMaxGridCells) {
      f_.fail("depth_grid", cat(g.columns, "x", g.rows, " cells is more than the ",
                                protocol::kMaxGridCells, " a message holds"));
    }
    number(n, "depth_grid", "min_depth_m", g.min_depth_m, 0.0, 1000.0);
    number(n, "depth_grid", "max_depth_m", g.max_depth_m, 0.001, 65.5);
    integer(n, "depth_grid", "min_confidence", g.min_confidence, 0, 255);
    if (g.max_depth_m <= g.min_depth_m) {
      f_.fail("depth_grid.max_depth_m", "must be greater than min_depth_m");
    }
  }

  void read_threads(const YAML::Node& root, BoardConfig& c) {
    const YAML::Node n =
        section(root, "threads", {"count", "affinity", "realtime_priority", "lock_memory", "maps"});
    int count = 0;  // not given: as many as the CPUs the firmware may run on
    integer(n, "threads", "count", count, 1, 64);
    if (n.IsDefined()) {
      if (const YAML::Node a = f_.optional_child(n, "threads", "affinity"); a.IsDefined()) {
        for (const double cpu : f_.numbers(a, "threads.affinity")) {
          if (cpu < 0 || cpu > 1023 || cpu != std::floor(cpu)) {
            f_.fail("threads.affinity", cat(cpu, " is not a CPU number (0..1023)"));
          }
          c.threads.affinity.push_back(static_cast<int>(cpu));
        }
      }
    }
    integer(n, "threads", "realtime_priority", c.threads.realtime_priority, 0, 99);
    boolean(n, "threads", "lock_memory", c.threads.lock_memory);
    if (n.IsDefined()) {
      f_.if_present(n, "threads", "maps", [&](const YAML::Node& v, const std::string& k) {
        const std::string value = f_.text(v, k);
        if (value != "idle" && value != "normal") f_.fail(k, "must be idle or normal");
        c.threads.maps_idle = value == "idle";
      });
    }
    const std::set<int> listed(c.threads.affinity.begin(), c.threads.affinity.end());
    const int cpus = listed.empty() ? usable_cpus() : static_cast<int>(listed.size());
    c.threads.count = count != 0 ? count : std::clamp(cpus, 1, 64);
  }

  // The sections backends read themselves: each one present, and each one a chosen backend needs
  // (which may say what is missing); the options given for the cameras go to theirs.
  void read_backend_sections(const YAML::Node& root, BoardConfig& c) {
    const hal::BackendRegistry& registry = hal::BackendRegistry::builtin();
    const char* cameras = registry.camera_traits(c.cameras.backend).section;
    const char* trigger = registry.trigger_traits(c.trigger.backend).section;
    const char* serial = registry.serial_traits(c.serial.backend).section;
    const std::vector<std::string> known = registry.camera_backends();
    const bool known_cameras =
        std::find(known.begin(), known.end(), c.cameras.backend) != known.end();
    // (An unknown backend is said by validate(), naming the known ones.)
    if (cameras == nullptr && known_cameras && !camera_options_.empty()) {
      f_.fail("cameras.backend",
              cat("'", c.cameras.backend, "' takes no option '", camera_options_.front().key, "'"));
    }
    for (const hal::SectionBackend& section : registry.sections()) {
      const YAML::Node n = f_.optional_child(root, "", section.name.c_str());
      const bool for_cameras = cameras != nullptr && section.name == cameras;
      const bool needed = for_cameras || (trigger != nullptr && section.name == trigger) ||
                          (serial != nullptr && section.name == serial);
      if (!n.IsDefined() && !needed) continue;
      c.sections.set(
          section.name,
          section.read(n, f_,
                       for_cameras ? camera_options_ : std::span<const hal::BackendOption>()));
    }
  }

  void only_known_keys(const YAML::Node& root) const {
    std::vector<std::string_view> known = {"version",          "name",
                                           "cameras",          "trigger",
                                           "pairing",          "serial",
                                           "calibration",      "stages",
                                           "corners",          "stereo",
                                           "sparse",           "calibration_health",
                                           "detector",         "obstacles",
                                           "depth_grid",       "threads",
                                           "memory_budget_mb", "snapshot_directory",
                                           "snapshot_limit",   "snapshot_min_free_mb",
                                           "outputs"};
    for (const hal::SectionBackend& section : hal::BackendRegistry::builtin().sections()) {
      known.push_back(section.name);
    }
    for (const stages::StageRow& row : stages::kPipelineStages) {
      if (row.definition->read_settings == nullptr) continue;
      const std::string_view name = protocol::stage_info(row.id).name;
      // Two readers of one section would each refuse the other's keys.
      require(std::find(known.begin(), known.end(), name) == known.end(), "stage ", name,
              ": its section '", name, "' is already the board reader's or a backend's");
      known.push_back(name);
    }
    f_.only_keys(root, "", known);
  }

  fs::path file_;
  yaml::Fields f_;
  std::span<const hal::BackendOption> camera_options_;
};

}  // namespace

std::string frame_timing_problem(hal::Nanoseconds period, hal::Nanoseconds exposure,
                                 hal::Nanoseconds camera_timeout) {
  const auto ms = [](hal::Nanoseconds ns) { return static_cast<double>(ns) / 1e6; };
  if (period > 0 && exposure >= period) {
    return cat("an exposure of ", ms(exposure), " ms does not fit in the frame period of ",
               ms(period), " ms");
  }
  if (period > 0 && period + exposure >= camera_timeout) {
    return cat("a frame every ", ms(period), " ms",
               exposure > 0 ? cat(" exposed ", ms(exposure), " ms") : "",
               " does not come within the cameras' timeout of ", ms(camera_timeout),
               " ms (cameras.timeout_ms): they would time out and be reopened again and again");
  }
  return {};
}

std::string watchdog_problem(const BoardConfig& c, hal::Nanoseconds watchdog_interval) {
  if (watchdog_interval <= 0 || 4 * c.cameras.timeout <= watchdog_interval) return {};
  return cat("cameras.timeout_ms ", c.cameras.timeout / 1'000'000,
             " is more than a quarter of the service's watchdog interval of ",
             watchdog_interval / 1'000'000,
             " ms (WatchdogSec): pings go at most every half interval, and a wait for a late pair "
             "with the processing after it could let the watchdog fire");
}

namespace {

// The checks across keys, each failing with the file and the key.
// The odometry goes out every pair: the stage on with what it reads, and a calibration (its
// points in metres).
bool odometry_sent(const BoardConfig& c) {
  constexpr protocol::StageMask needs = protocol::stage_bit(protocol::Stage::odometry) |
                                        protocol::stage_bit(protocol::Stage::sparse) |
                                        protocol::stage_bit(protocol::Stage::corners);
  return (c.stages & needs) == needs && !c.calibration.empty();
}

struct Checks {
  const BoardConfig& c;
  const std::string& file;

  [[noreturn]] void fail(const std::string& key, const std::string& message) const {
    throw Error(cat(file, ": ", key, ": ", message));
  }

  void backends() const {
    const hal::BackendRegistry& registry = hal::BackendRegistry::builtin();
    const auto known = [&](const char* key, const std::string& backend,
                           std::vector<std::string> names, bool none_allowed) {
      if (none_allowed) names.emplace_back(hal::kNoBackend);
      if (std::find(names.begin(), names.end(), backend) == names.end()) {
        std::string list;
        for (const std::string& n : names) list += (list.empty() ? "" : ", ") + n;
        fail(key, cat("'", backend, "' is not one of ", list));
      }
    };
    known("cameras.backend", c.cameras.backend, registry.camera_backends(), false);
    known("trigger.backend", c.trigger.backend, registry.trigger_backends(), true);
    known("serial.backend", c.serial.backend, registry.serial_backends(), true);
  }

  void pairing() const {
    if (c.has_trigger() && c.pairing.trigger_period > 0 &&
        2 * c.pairing.tolerance >= c.pairing.trigger_period) {
      fail(
          "pairing.tolerance_us",
          cat(c.pairing.tolerance / 1000, " us is not below half the trigger period (",
              c.pairing.trigger_period / 1000, " us): frames of neighbouring triggers could pair"));
    }
    if (c.has_trigger() && c.pairing.trigger_period > 0 &&
        2 * c.pairing.edge_tolerance >= c.pairing.trigger_period) {
      fail("pairing.edge_tolerance_us",
           cat(c.pairing.edge_tolerance / 1000, " us is not below half the trigger period"));
    }
    if (!c.has_trigger()) {  // free running: pairs are matched by time
      const double fps = std::max(c.cameras.left.fps, c.cameras.right.fps);
      if (2 * static_cast<double>(c.pairing.tolerance) >= 1e9 / fps) {
        fail("pairing.tolerance_us",
             cat(c.pairing.tolerance / 1000, " us is not below half the cameras' frame period (",
                 std::llround(1e6 / fps), " us at ", fps,
                 " fps): without a trigger, frames are paired by time"));
      }
    }
  }

  void frame_timing() const {
    for (const hal::CameraConfig* camera : {&c.cameras.left, &c.cameras.right}) {
      const hal::Nanoseconds period =
          c.has_trigger() ? c.pairing.trigger_period : hal::period_of(std::max(camera->fps, 1e-3));
      if (const std::string problem =
              frame_timing_problem(period, camera->exposure, c.cameras.timeout);
          !problem.empty()) {
        fail(c.has_trigger() ? "trigger.rate_hz" : "cameras.fps", problem);
      }
    }
  }

  void link() const {
    if (!c.has_link()) return;
    const LinkProtocol protocol = c.serial.protocol == BoardConfig::LinkProtocol::mavlink
                                      ? LinkProtocol::mavlink
                                      : LinkProtocol::epipole;
    if (const std::string problem =
            link_capacity_problem(protocol, c.serial.port.baud, c.frame_period(), odometry_sent(c));
        !problem.empty()) {
      fail("serial.baud", problem);
    }
  }

  void stages_and_threads() const {
    if (protocol::has_stage(c.stages, protocol::Stage::disparity) &&
        c.stereo.max_disparity >= c.width()) {
      fail("stereo.max_disparity",
           cat(c.stereo.max_disparity, " is not smaller than the width ", c.width()));
    }
    if (protocol::has_stage(c.stages, protocol::Stage::detect) && c.detector.max_size != 0 &&
        c.detector.max_size < c.detector.min_size) {
      fail("detector.max_size", "is smaller than min_size");
    }
    if (c.threads.realtime_priority > 0 && c.threads.realtime_priority > 99) {
      fail("threads.realtime_priority", "must be in 1..99");
    }
  }
};

}  // namespace

void validate(const BoardConfig& c, const std::string& file) {
  const Checks checks{c, file};
  if (c.cameras.left.width != c.cameras.right.width ||
      c.cameras.left.height != c.cameras.right.height) {
    checks.fail("cameras", "left and right cameras differ in size");
  }
  checks.backends();
  checks.pairing();
  checks.frame_timing();
  checks.link();
  checks.stages_and_threads();
}

BoardConfig parse_board_config(const std::string& yaml_text, const fs::path& file,
                               std::span<const hal::BackendOption> camera_options) {
  BoardConfig c = BoardReader(file, camera_options).read(yaml_text);
  validate(c, file.string());
  return c;
}

namespace {

fs::path board_file(const fs::path& path) {
  std::error_code ec;
  return fs::is_directory(path, ec) ? path / "board.yaml" : path;
}

// Sets one `KEY=VALUE` override in the board file's document.
void apply_override(YAML::Node root, const std::string& setting, const std::string& file) {
  const auto refuse = [&](const std::string& why) {
    return Error(cat(file, ": the override '", setting, "' ", why));
  };
  const std::size_t equals = setting.find('=');
  if (equals == std::string::npos || equals == 0) {
    throw refuse("is not KEY=VALUE (e.g. stereo.method=bm)");
  }
  std::vector<std::string> keys;
  for (std::size_t start = 0; start <= equals;) {
    const std::size_t end = std::min(setting.find('.', start), equals);
    keys.push_back(setting.substr(start, end - start));
    if (keys.back().empty()) throw refuse("has an empty key between its dots");
    start = end + 1;
  }
  YAML::Node value;
  try {
    value = YAML::Load(setting.substr(equals + 1));
  } catch (const YAML::Exception& e) {
    throw refuse(cat("has a value that is not YAML (", e.msg, ")"));
  }
  // Nodes are handles: reset() moves one to another node, where `=` would overwrite its value.
  YAML::Node node = root;
  std::string path;
  for (std::size_t i = 0; i + 1 < keys.size(); ++i) {
    path += (path.empty() ? "" : ".") + keys[i];
    YAML::Node child = node[keys[i]];
    if (!child.IsDefined() || child.IsNull()) {
      node[keys[i]] = YAML::Node(YAML::NodeType::Map);
      child.reset(node[keys[i]]);
    }
    if (!child.IsMap()) throw refuse(cat("sets a key inside ", path, ", which is not a map"));
    node.reset(child);
  }
  node[keys.back()] = value;
}

}  // namespace

BoardConfig load_board_config(const fs::path& path) {
  const fs::path file = board_file(path);
  return parse_board_config(read_text_file(file), file);
}

BoardConfig load_board_config(const fs::path& path, std::span<const std::string> overrides,
                              std::span<const hal::BackendOption> camera_options) {
  const fs::path file = board_file(path);
  if (overrides.empty()) return parse_board_config(read_text_file(file), file, camera_options);
  const YAML::Node root = yaml::Fields(file.string()).parse(read_text_file(file));
  if (!root.IsMap()) throw Error(cat(file.string(), ": expected a YAML map of keys"));
  for (const std::string& setting : overrides) apply_override(root, setting, file.string());
  return parse_board_config(YAML::Dump(root), file, camera_options);
}

}  // namespace epipole::firmware
