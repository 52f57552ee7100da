// The board file's `sim:` section, read by the simulated board itself.
#include "sim/sim_settings.hpp"

#include <yaml-cpp/yaml.h>

#include "epipole/core/error.hpp"
#include "epipole/core/yaml_fields.hpp"
#include "sim/world_settings.hpp"

namespace epipole::hal {

namespace {

constexpr const char* kSection = "sim";

SimDrift read_drift(const yaml::Fields& f, const YAML::Node& m, const std::string& p) {
  f.only_keys(m, p, {"pitch_deg", "roll_deg", "yaw_deg"});
  SimDrift d;
  for (auto [key, angle] : {std::pair{"pitch_deg", &d.pitch_deg},
                            std::pair{"roll_deg", &d.roll_deg}, std::pair{"yaw_deg", &d.yaw_deg}}) {
    f.if_present(m, p, key, [&, angle = angle](const YAML::Node& n, const std::string& k) {
      *angle = f.number_in(n, k, -10, 10);
    });
  }
  return d;
}

SimScene read_scene(const yaml::Fields& f, const std::string& name, const YAML::Node& m) {
  SimScene s;
  s.name = name;
  const std::string p = cat(kSection, ".scenes.", name);
  f.only_keys(m, p,
              {"left", "right", "side_by_side", "synthesize", "disparity", "recording", "world",
               "max_frames", "calibration", "drift"});
  f.if_present(m, p, "max_frames", [&](const YAML::Node& n, const std::string& k) {
    s.max_frames = f.integer_in(n, k, 1, 100'000);
  });
  std::string given;  // the scene's source: one of these
  for (const std::string source :
       {"world", "side_by_side", "synthesize", "recording", "left", "right"}) {
    if (!f.optional_child(m, p, source.c_str()).IsDefined() ||
        (source == "right" && given == "left")) {
      continue;
    }
    if (!given.empty()) f.fail(p, cat(given, " and ", source, " are two sources: give one"));
    given = source;
  }
  if (const YAML::Node world = f.optional_child(m, p, "world"); world.IsDefined()) {
    s.world = read_world(f, world, p + ".world");
  } else if (const YAML::Node v = f.optional_child(m, p, "side_by_side"); v.IsDefined()) {
    s.side_by_side = f.path(v, p + ".side_by_side");
  } else if (const YAML::Node r = f.optional_child(m, p, "recording"); r.IsDefined()) {
    s.recording = f.path(r, p + ".recording");
  } else if (const YAML::Node y = f.optional_child(m, p, "synthesize"); y.IsDefined()) {
    s.synthesize = f.path(y, p + ".synthesize");
    s.synthesize_disparity = f.integer(f.child(m, p, "disparity"), p + ".disparity");
    if (s.synthesize_disparity < 0 || s.synthesize_disparity > 255) {
      f.fail(p + ".disparity", "must be in 0..255");
    }
  } else {
    s.left = f.files(f.child(m, p, "left"), p + ".left");
    s.right = f.files(f.child(m, p, "right"), p + ".right");
    if (s.left.size() != s.right.size()) {
      f.fail(p, cat(s.left.size(), " left images but ", s.right.size(), " right images"));
    }
  }
  if (const YAML::Node v = f.optional_child(m, p, "calibration"); v.IsDefined()) {
    s.calibration = f.path(v, p + ".calibration");
  } else if (s.world) {
    f.fail(p + ".calibration",
           "a world scene needs its rig's calibration (the raw images are rendered through it)");
  }
  if (const YAML::Node d = f.optional_child(m, p, "drift"); d.IsDefined()) {
    s.drift = read_drift(f, d, p + ".drift");
    if (s.calibration.empty()) {
      f.fail(p + ".drift", "a drift needs the scene's calibration (the right camera's lens)");
    }
  }
  return s;
}

void choose_scene(const yaml::Fields& f, SimSettings& s, std::span<const BackendOption> options) {
  for (const BackendOption& option : options) {
    if (option.key != "scene") {
      f.fail(kSection, cat("the simulated board takes no option '", option.key, "'"));
    }
    s.scene = option.value;
  }
  if (s.scenes.empty()) f.fail("sim.scenes", "the simulated board needs at least one scene");
  if (s.scene.empty()) s.scene = s.scenes.front().name;
  std::string names;
  for (const SimScene& scene : s.scenes) {
    if (scene.name == s.scene) return;
    names += (names.empty() ? "" : ", ") + scene.name;
  }
  f.fail("sim.scene", cat("'", s.scene, "' is not a scene of this board (", names, ")"));
}

}  // namespace

std::unique_ptr<BackendSettings> read_sim_section(const YAML::Node& n, const yaml::Fields& f,
                                                  std::span<const BackendOption> options) {
  auto s = std::make_unique<SimSettings>();
  if (n.IsDefined()) {
    f.only_keys(n, kSection,
                {"scene", "scenes", "charge_compute", "drop_rate", "corrupt_rate", "seed"});
    f.if_present(n, kSection, "scene",
                 [&](const YAML::Node& v, const std::string& k) { s->scene = f.text(v, k); });
    f.if_present(n, kSection, "charge_compute", [&](const YAML::Node& v, const std::string& k) {
      s->charge_compute = f.boolean(v, k);
    });
    f.if_present(n, kSection, "drop_rate", [&](const YAML::Node& v, const std::string& k) {
      s->drop_rate = f.number_in(v, k, 0, 1);
    });
    f.if_present(n, kSection, "corrupt_rate", [&](const YAML::Node& v, const std::string& k) {
      s->corrupt_rate = f.number_in(v, k, 0, 1);
    });
    f.if_present(n, kSection, "seed", [&](const YAML::Node& v, const std::string& k) {
      s->seed = static_cast<std::uint64_t>(f.integer_in(v, k, 0, 1'000'000'000));
    });
    const YAML::Node scenes = f.child(n, kSection, "scenes");
    f.require_map(scenes, "sim.scenes");
    for (const auto& entry : scenes) {
      s->scenes.push_back(read_scene(f, entry.first.Scalar(), entry.second));
    }
  }
  choose_scene(f, *s, options);
  return s;
}

const SimScene& SimSettings::chosen() const {
  for (const SimScene& s : scenes) {
    if (s.name == scene) return s;
  }
  throw Error(cat("the simulated board has no scene '", scene, "'"));
}

std::filesystem::path SimSettings::calibration() const {
  for (const SimScene& s : scenes) {
    if (s.name == scene) return s.calibration.empty() ? s.recording : s.calibration;
  }
  return {};
}

std::unique_ptr<BackendSettings> SimSettings::clone() const {
  return std::make_unique<SimSettings>(*this);
}

SimSettings& sim_settings(BackendSections& sections) {
  return const_cast<SimSettings&>(sim_settings(std::as_const(sections)));
}

const SimSettings& sim_settings(const BackendSections& sections) {
  const auto* s = dynamic_cast<const SimSettings*>(sections.find(kSection));
  require(s != nullptr, "the board file has no '", kSection, "' section");
  return *s;
}

}  // namespace epipole::hal
