// libFuzzer target: arbitrary bytes into the compiled cascade loader, as they are and with the
// CRC repaired (so that mutations also reach the model checks behind it). A cascade it accepts
// must encode again to the same bytes (the format is canonical), and the detector must run it
// on a small image, on the reference and the fastest kernel path, with the same results.
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <span>
#include <vector>

#include "epipole/core/crc32.hpp"
#include "epipole/core/error.hpp"
#include "epipole/vision/cascade.hpp"
#include "epipole/vision/cascade_model.hpp"

namespace {

void check(const std::uint8_t* data, std::size_t size) {
  using namespace epipole;
  using namespace epipole::vision;
  try {
    const CascadeModel model = CascadeModel::from_binary({data, size}, "fuzz");
    if (model.to_binary() != std::vector<std::uint8_t>(data, data + size)) std::abort();
    if (model.window_width() > 40 || model.window_height() > 40) return;
    GrayImage image(48, 40);
    for (int y = 0; y < image.height(); ++y) {
      for (int x = 0; x < image.width(); ++x) {
        image(x, y) = static_cast<std::uint8_t>(data[(x * 7 + y * 13) % size] + x * y);
      }
    }
    CascadeConfig config;
    config.max_width = image.width();
    config.max_height = image.height();
    config.min_neighbors = 1;
    config.scale_factor = 1.2;
    CascadeDetector reference(model, config, SimdPath::reference);
    CascadeDetector fast(model, config);
    const auto a = reference.detect(image.view());
    const std::vector<Detection> expected(a.begin(), a.end());
    const auto b = fast.detect(image.view());
    if (std::vector<Detection>(b.begin(), b.end()) != expected) std::abort();
  } catch (const epipole::Error&) {
    // Bad input is an Error: that is what the loader must do.
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  check(data, size);
  constexpr std::size_t kHeader = 40;
  if (size < kHeader) return 0;
  std::vector<std::uint8_t> repaired(data, data + size);
  const std::span<const std::uint8_t> bytes(repaired);
  const std::uint32_t crc = epipole::crc32(bytes.subspan(kHeader), epipole::crc32(bytes.first(36)));
  for (int i = 0; i < 4; ++i) repaired[36 + i] = static_cast<std::uint8_t>(crc >> (8 * i));
  check(repaired.data(), repaired.size());
  return 0;
}
