#pragma once

// Whole text files in and out, with errors that name the file: configuration, calibration and
// the exports other tools read.

#include <filesystem>
#include <string>

namespace epipole {

// The whole file as text. A file that cannot be opened or read is an Error naming it.
std::string read_text_file(const std::filesystem::path& file);

// Writes `text` to a temporary file beside `file` and renames it over `file`, so that a reader
// never sees half a file. Throws Error naming the file.
void write_text_file_atomically(const std::filesystem::path& file, const std::string& text);

// Makes the folder and its parents when missing; Error naming it when that fails or the path
// is not a folder.
void make_directories(const std::filesystem::path& directory);

}  // namespace epipole
