#pragma once

#include <sstream>
#include <stdexcept>
#include <string>
#include <utility>

namespace epipole {

// The one exception type of the project. It is thrown for bad input (a file, a configuration,
// an argument, mismatched image sizes) with a message that names what was wrong; it is never
// thrown by a correctly configured frame loop.
class Error : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// Builds a message from any streamable parts: throw Error(cat("width ", w, " < 3")).
template <typename... Parts>
std::string cat(Parts&&... parts) {
  std::ostringstream out;
  (out << ... << std::forward<Parts>(parts));
  return out.str();
}

// Throws Error(message parts...) when the condition does not hold.
template <typename... Parts>
void require(bool condition, Parts&&... parts) {
  if (!condition) throw Error(cat(std::forward<Parts>(parts)...));
}

}  // namespace epipole
