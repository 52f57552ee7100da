#include "epipole/core/image_io.hpp"

#include <gtest/gtest.h>

#include <fstream>
#include <random>

#include "epipole/core/crc32.hpp"
#include "epipole/core/error.hpp"

namespace epipole {
namespace {

namespace fs = std::filesystem;

class ImageFiles : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("epipole-io-" + std::to_string(::testing::UnitTest::GetInstance()->random_seed()) +
            "-" + ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  fs::path file(const std::string& name) const { return dir_ / name; }
  void write_bytes(const fs::path& path, const std::string& bytes) const {
    std::ofstream(path, std::ios::binary) << bytes;
  }

  fs::path dir_;
};

template <typename T>
Image<T> random_image(int width, int height, unsigned seed) {
  Image<T> image(width, height);
  std::mt19937 rng(seed);
  for (int y = 0; y < height; ++y)
    for (int x = 0; x < width; ++x) image(x, y) = static_cast<T>(rng());
  return image;
}

template <typename T>
void expect_same(const Image<T>& a, const Image<T>& b) {
  ASSERT_EQ(a.width(), b.width());
  ASSERT_EQ(a.height(), b.height());
  for (int y = 0; y < a.height(); ++y)
    for (int x = 0; x < a.width(); ++x) ASSERT_EQ(a(x, y), b(x, y)) << x << "," << y;
}

TEST_F(ImageFiles, GrayRoundTrips) {
  const GrayImage image = random_image<std::uint8_t>(37, 19, 1);
  for (const char* name : {"a.png", "a.pgm", "A.PNG"}) {
    save_image(file(name), image.view());
    expect_same(load_gray(file(name)), image);
  }
}

TEST_F(ImageFiles, SixteenBitRoundTrips) {
  const Image<std::uint16_t> image = random_image<std::uint16_t>(23, 7, 2);
  for (const char* name : {"d.png", "d.pgm"}) {
    save_image(file(name), image.view());
    expect_same(load_gray16(file(name)), image);
    // Loaded as 8 bit, a 16-bit sample keeps its high byte.
    const GrayImage narrow = load_gray(file(name));
    EXPECT_EQ(narrow(5, 3), image(5, 3) >> 8);
  }
}

TEST_F(ImageFiles, EightBitSamplesKeepTheirValuesWhenReadFor16Bits) {
  // Middlebury's ground truth: 8-bit disparities in pixels, read as they are, from PNG as from
  // PGM.
  const GrayImage image = random_image<std::uint8_t>(21, 5, 3);
  for (const char* name : {"g.png", "g.pgm"}) {
    save_image(file(name), image.view());
    const Image<std::uint16_t> wide = load_gray16(file(name));
    ASSERT_EQ(wide.width(), 21);
    for (int y = 0; y < 5; ++y) {
      for (int x = 0; x < 21; ++x)
        ASSERT_EQ(wide(x, y), image(x, y)) << name << " " << x << "," << y;
    }
  }
}

TEST_F(ImageFiles, RgbIsWrittenAndReadAsGray) {
  RgbImage image(4, 2);
  for (int y = 0; y < 2; ++y)
    for (int x = 0; x < 4; ++x) image(x, y) = {200, 100, 50};
  save_image(file("c.png"), ImageView<const Rgb8>(image.view()));
  const GrayImage gray = load_gray(file("c.png"));
  // 0.299 * 200 + 0.587 * 100 + 0.114 * 50 = 124.2
  EXPECT_NEAR(gray(1, 1), 124, 1);
  save_image(file("c.ppm"), ImageView<const Rgb8>(image.view()));
  EXPECT_GT(fs::file_size(file("c.ppm")), 24u);
}

TEST_F(ImageFiles, BadFilesGiveErrorsNamingTheFile) {
  write_bytes(file("text.png"), "this is not an image");
  write_bytes(file("truncated.png"), std::string("\x89PNG\r\n\x1a\n\0\0\0\rIHDR", 16));
  write_bytes(file("truncated.jpg"), std::string("\xFF\xD8\xFF\xE0\0\x10JFIF", 10));
  write_bytes(file("bad.pgm"), "P5\n12 x\n255\n");
  write_bytes(file("short.pgm"), "P5\n4 4\n255\nabc");
  write_bytes(file("huge.pgm"), "P5\n99999999 4\n255\n");
  write_bytes(file("empty.png"), "");
  for (const char* name : {"text.png", "truncated.png", "truncated.jpg", "bad.pgm", "short.pgm",
                           "huge.pgm", "empty.png", "missing.png"}) {
    try {
      (void)load_gray(file(name));
      ADD_FAILURE() << name << " loaded";
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find(name), std::string::npos) << e.what();
    }
  }
}

// A PNG whose header claims width x height, and no pixels.
std::string png_header(std::uint32_t width, std::uint32_t height) {
  std::string chunk = "IHDR";
  for (const std::uint32_t v : {width, height}) {
    for (int shift = 24; shift >= 0; shift -= 8) chunk += static_cast<char>((v >> shift) & 0xFF);
  }
  chunk += std::string("\x08\x00\x00\x00\x00", 5);  // 8-bit gray, no interlace
  const std::uint32_t crc =
      crc32(std::span(reinterpret_cast<const std::uint8_t*>(chunk.data()), chunk.size()));
  std::string png = std::string("\x89PNG\r\n\x1a\n\0\0\0\x0d", 12) + chunk;
  for (int shift = 24; shift >= 0; shift -= 8) png += static_cast<char>((crc >> shift) & 0xFF);
  // An empty IDAT (libpng reads the header up to the first one): length 0, type, CRC.
  return png + std::string("\0\0\0\0IDAT\x35\xaf\x06\x1e", 12);
}

TEST_F(ImageFiles, AHeaderClaimingAHugeImageIsAnErrorBeforeAnyAllocation) {
  // Found by image_fuzz: a few bytes of PGM header asked for gigabytes.
  write_bytes(file("vast.pgm"), "P5\n900000 900000\n255\nxyz");
  write_bytes(file("claims.pgm"), "P5\n4000 4000\n65535\n0123456789");
  write_bytes(file("vast.png"), png_header(100'000, 100'000));
  const auto error_of = [&](const char* name) {
    try {
      (void)load_gray16(file(name));
    } catch (const Error& e) {
      return std::string(e.what());
    }
    return std::string("loaded");
  };
  EXPECT_NE(error_of("vast.pgm")
                .find("vast.pgm: PGM size 900000x900000 is more than the 67108864 "
                      "pixels an image may have"),
            std::string::npos)
      << error_of("vast.pgm");
  EXPECT_NE(error_of("claims.pgm")
                .find("claims.pgm: PGM data ends early: 4000x4000 samples need "
                      "32000000 bytes, the file has 10 after its header"),
            std::string::npos)
      << error_of("claims.pgm");
  EXPECT_NE(error_of("vast.png").find("vast.png: PNG size 100000x100000 is more than"),
            std::string::npos)
      << error_of("vast.png");
}

TEST_F(ImageFiles, WritingRejectsUnknownExtensionsAndMissingFolders) {
  const GrayImage image = random_image<std::uint8_t>(4, 4, 3);
  EXPECT_THROW(save_image(file("x.bmp"), image.view()), Error);
  EXPECT_THROW(save_image(file("no/such/dir/x.png"), image.view()), Error);
  const GrayImage empty;
  EXPECT_THROW(save_image(file("e.png"), empty.view()), Error);
}

}  // namespace
}  // namespace epipole
