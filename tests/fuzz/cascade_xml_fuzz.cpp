// libFuzzer target: arbitrary bytes into the OpenCV cascade XML reader. A cascade it accepts
// must compile to a binary that reads back as the same cascade.
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <string_view>

#include "epipole/core/error.hpp"
#include "epipole/tools/cascade_xml.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace epipole;
  try {
    const vision::CascadeModel model = tools::parse_cascade_xml(
        std::string_view(reinterpret_cast<const char*>(data), size), "fuzz.xml");
    const vision::CascadeModel again =
        vision::CascadeModel::from_binary(model.to_binary(), "compiled");
    if (!(again.data() == model.data())) std::abort();
  } catch (const Error&) {
    // Bad input is an Error: that is what the reader must do.
  }
  return 0;
}
