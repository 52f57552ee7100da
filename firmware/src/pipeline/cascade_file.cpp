#include "epipole/firmware/cascade_file.hpp"

#include <fstream>
#include <iterator>
#include <vector>

#include "epipole/core/data_directory.hpp"
#include "epipole/core/error.hpp"

namespace epipole::firmware {

vision::CascadeModel load_compiled_cascade(const std::filesystem::path& file) {
  std::ifstream in(file, std::ios::binary);
  require(static_cast<bool>(in), file.string(), ": cannot open");
  const std::vector<std::uint8_t> bytes((std::istreambuf_iterator<char>(in)),
                                        std::istreambuf_iterator<char>());
  require(!in.bad(), file.string(), ": read error");
  return vision::CascadeModel::from_binary(bytes, file.string());
}

std::filesystem::path opencv_cascade_xml(const std::filesystem::path& compiled) {
  for (const char* family : {"haarcascades", "lbpcascades"}) {
    std::filesystem::path candidate = default_data_directory() / "cascades" / family;
    candidate /= compiled.stem().string() + ".xml";
    std::error_code ec;
    if (std::filesystem::exists(candidate, ec)) return candidate;
  }
  return {};
}

std::string cascade_compile_command(const std::filesystem::path& compiled) {
  const std::filesystem::path xml = opencv_cascade_xml(compiled);
  return cat("epipole cascade-compile ", xml.empty() ? "CASCADE.xml" : xml.string(), " ",
             compiled.string());
}

}  // namespace epipole::firmware
