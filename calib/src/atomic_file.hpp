#pragma once

#include <filesystem>
#include <string>

namespace epipole::calib::detail {

// Writes `text` to a temporary file beside `file` and renames it over `file`, so that a reader
// never sees half a file. Throws Error naming the file.
void write_atomically(const std::filesystem::path& file, const std::string& text);

}  // namespace epipole::calib::detail
