#include "epipole/core/simd.hpp"

#include <gtest/gtest.h>

#include "epipole/core/error.hpp"

namespace epipole {
namespace {

TEST(SimdPath, ParsesNames) {
  EXPECT_EQ(parse_simd_path("ref"), SimdPath::reference);
  EXPECT_EQ(parse_simd_path("reference"), SimdPath::reference);
  EXPECT_EQ(parse_simd_path("auto"), best_simd_path());
  if (cpu_has_neon()) {
    EXPECT_EQ(parse_simd_path("neon"), SimdPath::neon);
  }
  EXPECT_EQ(to_string(SimdPath::neon), "neon");
  EXPECT_EQ(to_string(SimdPath::reference), "ref");
}

TEST(SimdPath, RejectsUnknownNames) {
  try {
    parse_simd_path("avx9");
    FAIL() << "no exception";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("avx9"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace epipole
