// libFuzzer target: arbitrary text as a board file. It is read and validated, or refused with an
// Error naming the file; a board it accepts is valid (validate() agrees) and its timing fits.
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <string>

#include "epipole/core/error.hpp"
#include "epipole/firmware/board_config.hpp"
#include "fuzz_file.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace epipole;
  const std::filesystem::path file = fuzz::folder() / "board.yaml";
  try {
    const firmware::BoardConfig c =
        firmware::parse_board_config(std::string(reinterpret_cast<const char*>(data), size), file);
    firmware::validate(c, file.string());  // an accepted board passes its own validation
    if (c.width() <= 0 || c.height() <= 0) std::abort();
  } catch (const Error& e) {
    if (std::string(e.what()).find("board.yaml") == std::string::npos) std::abort();
  }
  return 0;
}
