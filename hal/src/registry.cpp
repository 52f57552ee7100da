#include "epipole/hal/registry.hpp"

#include <algorithm>

#include "backends.hpp"
#include "epipole/core/error.hpp"

namespace epipole::hal {

namespace {

template <typename Entries>
std::string names_of(const Entries& entries) {
  std::string names;
  for (const auto& e : entries) {
    if (!names.empty()) names += ", ";
    names += e.name;
    if (!e.unavailable.empty()) names += " (not built)";
  }
  return names;
}

template <typename Entries>
const auto& find_entry(const Entries& entries, std::string_view kind, std::string_view backend,
                       const std::string& target) {
  const auto it = std::find_if(entries.begin(), entries.end(),
                               [&](const auto& e) { return e.name == backend; });
  if (it == entries.end()) {
    throw Error(cat(kind, " ", target, ": unknown backend '", backend,
                    "' (known: ", names_of(entries), ")"));
  }
  if (!it->unavailable.empty()) {
    throw Error(cat(kind, " ", target, ": backend '", backend,
                    "' is not built into this binary: ", it->unavailable));
  }
  return *it;
}

BackendRegistry make_builtin() {
  BackendRegistry r;
  register_builtin_backends(r);
  return r;
}

}  // namespace

void BackendRegistry::add_camera(std::string name, CameraFactory factory, BackendTraits traits) {
  cameras_.push_back({std::move(name), std::move(factory), {}, traits});
}
void BackendRegistry::add_trigger(std::string name, TriggerFactory factory, BackendTraits traits) {
  triggers_.push_back({std::move(name), std::move(factory), {}, traits});
}
void BackendRegistry::add_serial(std::string name, SerialFactory factory, BackendTraits traits) {
  serials_.push_back({std::move(name), std::move(factory), {}, traits});
}
void BackendRegistry::add_unavailable_camera(std::string name, std::string reason,
                                             BackendTraits traits) {
  cameras_.push_back({std::move(name), {}, std::move(reason), traits});
}
void BackendRegistry::add_unavailable_trigger(std::string name, std::string reason,
                                              BackendTraits traits) {
  triggers_.push_back({std::move(name), {}, std::move(reason), traits});
}

void BackendRegistry::add_section(SectionBackend section) {
  sections_.push_back(std::move(section));
}

const SectionBackend* BackendRegistry::section(std::string_view name) const {
  const auto it = std::find_if(sections_.begin(), sections_.end(),
                               [&](const SectionBackend& s) { return s.name == name; });
  return it != sections_.end() ? &*it : nullptr;
}

std::unique_ptr<CameraSource> BackendRegistry::create_camera(std::string_view backend,
                                                             const CameraConfig& config,
                                                             const BackendContext& context) const {
  const auto& e = find_entry(cameras_, "camera", backend, config.device);
  validate(config);
  return e.factory(config, context);
}

std::unique_ptr<TriggerLine> BackendRegistry::create_trigger(std::string_view backend,
                                                             const TriggerConfig& config,
                                                             const BackendContext& context) const {
  const auto& e = find_entry(triggers_, "trigger", backend, config.line);
  validate(config);
  return e.factory(config, context);
}

std::unique_ptr<SerialPort> BackendRegistry::create_serial(std::string_view backend,
                                                           const SerialConfig& config,
                                                           const BackendContext& context) const {
  const auto& e = find_entry(serials_, "serial port", backend, config.device);
  return e.factory(config, context);
}

namespace {

template <typename Entries>
std::vector<std::string> name_list(const Entries& entries) {
  std::vector<std::string> names;
  for (const auto& e : entries) names.push_back(e.name);
  return names;
}

template <typename Entries>
BackendTraits traits_of(const Entries& entries, std::string_view backend) {
  for (const auto& e : entries) {
    if (e.name == backend) return e.traits;
  }
  return {};
}

}  // namespace

std::vector<std::string> BackendRegistry::camera_backends() const {
  return name_list(cameras_);
}
std::vector<std::string> BackendRegistry::trigger_backends() const {
  return name_list(triggers_);
}
std::vector<std::string> BackendRegistry::serial_backends() const {
  return name_list(serials_);
}
BackendTraits BackendRegistry::camera_traits(std::string_view backend) const {
  return traits_of(cameras_, backend);
}
BackendTraits BackendRegistry::trigger_traits(std::string_view backend) const {
  return traits_of(triggers_, backend);
}
BackendTraits BackendRegistry::serial_traits(std::string_view backend) const {
  return traits_of(serials_, backend);
}

const BackendRegistry& BackendRegistry::builtin() {
  static const BackendRegistry registry = make_builtin();
  return registry;
}

}  // namespace epipole::hal
