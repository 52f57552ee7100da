#include "epipole/hal/backend_settings.hpp"

#include <algorithm>

namespace epipole::hal {

BackendSections::BackendSections(const BackendSections& other) {
  *this = other;
}

BackendSections& BackendSections::operator=(const BackendSections& other) {
  if (this == &other) return *this;
  std::vector<std::pair<std::string, std::unique_ptr<BackendSettings>>> copy;
  for (const auto& [name, settings] : other.sections_) {
    copy.emplace_back(name, settings ? settings->clone() : nullptr);
  }
  sections_ = std::move(copy);  // a clone that throws leaves this as it was
  return *this;
}

const BackendSettings* BackendSections::find(std::string_view name) const {
  const auto it = std::find_if(sections_.begin(), sections_.end(),
                               [&](const auto& s) { return s.first == name; });
  return it != sections_.end() ? it->second.get() : nullptr;
}

BackendSettings* BackendSections::find(std::string_view name) {
  return const_cast<BackendSettings*>(std::as_const(*this).find(name));
}

void BackendSections::set(std::string name, std::unique_ptr<BackendSettings> settings) {
  for (auto& s : sections_) {
    if (s.first == name) {
      s.second = std::move(settings);
      return;
    }
  }
  sections_.emplace_back(std::move(name), std::move(settings));
}

}  // namespace epipole::hal
