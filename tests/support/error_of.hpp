#pragma once

// The message of the epipole::Error that `f` throws, or "" when it throws none.
#include <functional>
#include <string>

#include "epipole/core/error.hpp"

namespace epipole::test {

inline std::string error_of(const std::function<void()>& f) {
  try {
    f();
  } catch (const Error& e) {
    return e.what();
  }
  return "";
}

}  // namespace epipole::test
