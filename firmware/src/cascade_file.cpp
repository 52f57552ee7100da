#include "epipole/firmware/cascade_file.hpp"

#include <fstream>
#include <iterator>
#include <vector>

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

}  // namespace epipole::firmware
