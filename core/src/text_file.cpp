#include "epipole/core/text_file.hpp"

#include <unistd.h>

#include <fstream>
#include <sstream>
#include <system_error>

#include "epipole/core/error.hpp"

namespace epipole {

std::string read_text_file(const std::filesystem::path& file) {
  std::ifstream in(file, std::ios::binary);
  require(in.good(), file.string(), ": cannot open the file");
  std::ostringstream text;
  text << in.rdbuf();
  require(!in.bad(), file.string(), ": read error");
  return text.str();
}

void write_text_file_atomically(const std::filesystem::path& file, const std::string& text) {
  std::filesystem::path temporary = file;
  temporary += cat(".tmp", ::getpid());
  {
    std::ofstream out(temporary, std::ios::binary | std::ios::trunc);
    require(out.good(), file.string(), ": cannot write the file");
    out << text;
    out.close();
    if (!out) {
      std::error_code ignored;
      std::filesystem::remove(temporary, ignored);
      throw Error(cat(file.string(), ": write error"));
    }
  }
  std::error_code error;
  std::filesystem::rename(temporary, file, error);
  if (error) {
    std::error_code ignored;
    std::filesystem::remove(temporary, ignored);
    throw Error(cat(file.string(), ": cannot write the file (", error.message(), ")"));
  }
}

void make_directories(const std::filesystem::path& directory) {
  std::error_code error;
  std::filesystem::create_directories(directory, error);
  require(!error && std::filesystem::is_directory(directory), directory.string(),
          ": cannot make the folder", error ? " (" + error.message() + ")" : std::string());
}

}  // namespace epipole
