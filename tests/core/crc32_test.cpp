// CRC-32 (core): the standard check value, the empty input, a CRC continued over pieces.
#include <gtest/gtest.h>

#include <cstdint>
#include <string_view>

#include "epipole/core/crc32.hpp"

namespace epipole {
namespace {

TEST(Crc32, StandardCheckValue) {
  constexpr std::string_view text = "123456789";
  EXPECT_EQ(crc32(std::span(reinterpret_cast<const std::uint8_t*>(text.data()), text.size())),
            0xCBF43926u);
  EXPECT_EQ(crc32({}), 0u);
}

TEST(Crc32, ContinuesOverPieces) {
  constexpr std::string_view text = "123456789";
  const auto* bytes = reinterpret_cast<const std::uint8_t*>(text.data());
  for (std::size_t split = 0; split <= text.size(); ++split) {
    EXPECT_EQ(crc32(std::span(bytes + split, text.size() - split), crc32(std::span(bytes, split))),
              0xCBF43926u)
        << split;
  }
}

}  // namespace
}  // namespace epipole
