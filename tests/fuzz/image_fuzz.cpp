// libFuzzer target: arbitrary bytes as an image file (PNG, JPEG or PGM, told by their first
// bytes), read as 8-bit and 16-bit gray. A read image has a positive size within the reader's
// limits, and every pixel can be read; a bad file is an Error.
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <span>

#include "epipole/core/error.hpp"
#include "epipole/core/image_io.hpp"
#include "fuzz_file.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace epipole;
  const std::filesystem::path file = fuzz::write_file("image", std::span(data, size));
  unsigned sum = 0;
  try {
    const GrayImage image = load_gray(file);
    if (image.width() <= 0 || image.height() <= 0) std::abort();
    for (int y = 0; y < image.height(); ++y) sum += image.view().row(y)[image.width() - 1];
  } catch (const Error&) {
  }
  try {
    const Image<std::uint16_t> image = load_gray16(file);
    if (image.width() <= 0 || image.height() <= 0) std::abort();
    for (int y = 0; y < image.height(); ++y) sum += image.view().row(y)[image.width() - 1];
  } catch (const Error&) {
  }
  return static_cast<int>(sum & 0);
}
