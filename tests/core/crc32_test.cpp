// CRC-32 (core): the standard check value, and the empty input.
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

}  // namespace
}  // namespace epipole
