#pragma once

// Sections of a configuration file that their owners read themselves (a backend's, a stage's),
// kept by name as the owner read them. Everyone else only copies them and hands them back; a
// copy copies the settings (Settings::clone()).

#include <algorithm>
#include <memory>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace epipole {

template <class Settings>
class SettingsSections {
 public:
  SettingsSections() = default;
  SettingsSections(const SettingsSections& other) { *this = other; }
  SettingsSections& operator=(const SettingsSections& other) {
    if (this == &other) return *this;
    std::vector<Entry> copy;
    for (const auto& [name, settings] : other.sections_) {
      copy.emplace_back(name, settings ? settings->clone() : nullptr);
    }
    sections_ = std::move(copy);  // a clone that throws leaves this as it was
    return *this;
  }
  SettingsSections(SettingsSections&&) noexcept = default;
  SettingsSections& operator=(SettingsSections&&) noexcept = default;
  ~SettingsSections() = default;

  bool empty() const { return sections_.empty(); }
  const Settings* find(std::string_view name) const {
    const auto it = std::find_if(sections_.begin(), sections_.end(),
                                 [&](const Entry& s) { return s.first == name; });
    return it != sections_.end() ? it->second.get() : nullptr;
  }
  Settings* find(std::string_view name) {
    return const_cast<Settings*>(std::as_const(*this).find(name));
  }
  // Adds the section, or replaces the one of that name.
  void set(std::string name, std::unique_ptr<Settings> settings) {
    for (Entry& s : sections_) {
      if (s.first == name) {
        s.second = std::move(settings);
        return;
      }
    }
    sections_.emplace_back(std::move(name), std::move(settings));
  }

 private:
  using Entry = std::pair<std::string, std::unique_ptr<Settings>>;
  std::vector<Entry> sections_;
};

}  // namespace epipole
