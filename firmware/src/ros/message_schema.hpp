#pragma once

// How the `ros2msg` schemas of the messages are written: the message's definition, then each
// type it uses after a line of 80 '=' and "MSG: pkg/Type" (as ROS 2's own MCAP writer does).
#include <initializer_list>
#include <string>
#include <string_view>

namespace epipole::firmware::ros {

inline constexpr std::string_view kTime = "int32 sec\nuint32 nanosec\n";
inline constexpr std::string_view kHeader = "builtin_interfaces/Time stamp\nstring frame_id\n";

struct Dependency {
  std::string_view name;
  std::string_view definition;
};

inline constexpr Dependency kHeaderDeps[] = {{"std_msgs/Header", kHeader},
                                             {"builtin_interfaces/Time", kTime}};

// The definition, then each dependency after its separator line, into `storage`.
inline std::string_view schema(std::string& storage, std::string_view definition,
                               std::initializer_list<Dependency> dependencies) {
  storage = definition;
  for (const Dependency& d : dependencies) {
    storage += std::string(80, '=');
    storage += "\nMSG: ";
    storage += d.name;
    storage += '\n';
    storage += d.definition;
  }
  return storage;
}

}  // namespace epipole::firmware::ros
