// Videos decoded by the simulated board's loader (FFmpeg, hal/src/video_decoder.cpp) against
// OpenCV's VideoCapture + cvtColor(BGR2GRAY) on the same files, and every bad video an error.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iostream>
#include <string>
#include <vector>

#include <opencv2/imgproc.hpp>
#include <opencv2/videoio.hpp>

#include "epipole/core/error.hpp"
#include "error_of.hpp"
#include "sim/sim_files.hpp"
#include "test_data.hpp"

namespace epipole::hal {
namespace {

namespace fs = std::filesystem;

std::vector<cv::Mat> opencv_gray_frames(const fs::path& file) {
  cv::VideoCapture capture(file.string(), cv::CAP_FFMPEG);
  std::vector<cv::Mat> frames;
  cv::Mat bgr;
  while (capture.read(bgr)) {
    cv::Mat gray;
    cv::cvtColor(bgr, gray, cv::COLOR_BGR2GRAY);
    frames.push_back(gray);
  }
  return frames;
}

using test::error_of;

// The two conversions differ: ours takes the luma plane (expanded to full range by swscale),
// OpenCV converts to BGR and back to gray. Measured on the sample videos (mean, max of
// |ours - OpenCV| over every pixel of every frame): Megamind.avi 1.00, 14; vtest.avi 1.22, 24.
// The bounds: mean 1.5, max 32. (tree.avi is truncated: see the errors below.)
struct Reference {
  const char* file;
  double mean_bound;
  int max_bound;
};

class VideoAgainstOpenCV : public ::testing::TestWithParam<Reference> {};

TEST_P(VideoAgainstOpenCV, SameFramesWithinTheStatedTolerance) {
  const fs::path file = test::data_file(std::string("samples/") + GetParam().file);
  const std::vector<cv::Mat> reference = opencv_gray_frames(file);
  ASSERT_FALSE(reference.empty());
  VideoOptions options;
  options.max_frames = 2000;
  const std::vector<GrayImage> ours = load_video_gray(file, options);
  ASSERT_EQ(ours.size(), reference.size());
  double sum = 0;
  int max = 0;
  std::size_t count = 0;
  for (std::size_t i = 0; i < ours.size(); ++i) {
    ASSERT_EQ(ours[i].width(), reference[i].cols) << i;
    ASSERT_EQ(ours[i].height(), reference[i].rows) << i;
    for (int y = 0; y < reference[i].rows; ++y) {
      for (int x = 0; x < reference[i].cols; ++x) {
        const int d = std::abs(ours[i](x, y) - reference[i].at<std::uint8_t>(y, x));
        sum += d;
        max = std::max(max, d);
        ++count;
      }
    }
  }
  const double mean = sum / static_cast<double>(count);
  std::cout << GetParam().file << ": " << ours.size() << " frames of " << ours[0].width() << "x"
            << ours[0].height() << ", |ours - OpenCV| mean " << mean << " max " << max << "\n";
  EXPECT_LE(mean, GetParam().mean_bound);
  EXPECT_LE(max, GetParam().max_bound);
}

INSTANTIATE_TEST_SUITE_P(Samples, VideoAgainstOpenCV,
                         ::testing::Values(Reference{"Megamind.avi", 1.5, 32},
                                           Reference{"vtest.avi", 1.5, 32}),
                         [](const ::testing::TestParamInfo<Reference>& p) {
                           const std::string name = p.param.file;
                           return name.substr(0, name.find('.'));
                         });

// Writes frames (gray) with OpenCV's VideoWriter, losslessly (FFV1), into the test's folder.
fs::path write_video(const std::string& name, const std::vector<cv::Mat>& frames) {
  const fs::path file = fs::path(::testing::TempDir()) / name;
  cv::VideoWriter writer(file.string(), cv::CAP_FFMPEG, cv::VideoWriter::fourcc('F', 'F', 'V', '1'),
                         25.0, frames.front().size(), false);
  EXPECT_TRUE(writer.isOpened()) << file;
  for (const cv::Mat& f : frames) writer.write(f);
  return file;
}

TEST(Video, SideBySideSplitsBackIntoItsHalves) {
  std::vector<cv::Mat> source = opencv_gray_frames(test::data_file("samples/Megamind.avi"));
  ASSERT_GE(source.size(), 12u);
  source.resize(12);
  std::vector<cv::Mat> joined;
  const int half = source[0].cols / 2;
  for (std::size_t i = 0; i < source.size(); ++i) {
    cv::Mat both;  // the left view: frame i's left part; the right view: frame i+1's, flipped
    cv::Mat right;
    cv::flip(source[(i + 1) % source.size()](cv::Rect(0, 0, half, source[0].rows)), right, 1);
    cv::hconcat(source[i](cv::Rect(0, 0, half, source[0].rows)), right, both);
    joined.push_back(both);
  }
  const StereoImages split = load_side_by_side_video(write_video("sbs.avi", joined));
  ASSERT_EQ(split.left.size(), joined.size());
  for (std::size_t i = 0; i < joined.size(); ++i) {
    ASSERT_EQ(split.left[i].width(), half);
    ASSERT_EQ(split.right[i].width(), half);
    ASSERT_EQ(split.left[i].height(), source[0].rows);
    int differ = 0;
    for (int y = 0; y < joined[i].rows; ++y) {
      for (int x = 0; x < half; ++x) {
        differ += split.left[i](x, y) != joined[i].at<std::uint8_t>(y, x);
        differ += split.right[i](x, y) != joined[i].at<std::uint8_t>(y, x + half);
      }
    }
    EXPECT_EQ(differ, 0) << "frame " << i << " (FFV1 is lossless)";
  }
}

TEST(Video, StereoVideosPairFrameByFrameAndTheShorterSetsTheLength) {
  const fs::path megamind = test::data_file("samples/Megamind.avi");
  std::vector<cv::Mat> frames = opencv_gray_frames(megamind);
  frames.resize(5);
  const fs::path shorter = write_video("short.avi", frames);
  VideoOptions options;
  options.fit_width = 320;
  options.fit_height = 240;
  const StereoImages pair = load_stereo_videos(megamind, shorter, options);
  ASSERT_EQ(pair.left.size(), 5u);
  ASSERT_EQ(pair.right.size(), 5u);
  EXPECT_EQ(pair.left[0].width(), 320);
  EXPECT_EQ(pair.right[4].height(), 240);
  const StereoImages synth = synthesize_stereo_video(shorter, 7, options);
  ASSERT_EQ(synth.left.size(), 5u);
  EXPECT_EQ(synth.right[2](100, 120), synth.left[2](107, 120));
}

TEST(Video, EveryBadVideoIsAnErrorNamingTheFile) {
  const fs::path dir = ::testing::TempDir();
  const fs::path megamind = test::data_file("samples/Megamind.avi");
  const auto copy = [&](const fs::path& from, const std::string& name, std::size_t bytes) {
    std::ifstream in(from, std::ios::binary);
    std::string data((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    const fs::path to = dir / name;
    std::ofstream(to, std::ios::binary) << data.substr(0, std::min(bytes, data.size()));
    return to;
  };
  const fs::path renamed = copy(test::data_file("samples/aloeGT.png"), "picture.avi", 1u << 30);
  const fs::path truncated = copy(megamind, "truncated.avi", fs::file_size(megamind) / 2);
  const fs::path sound = dir / "sound.wav";  // a valid WAV: 8-bit mono PCM, no video
  {
    std::string wav =
        "RIFF" + std::string("\x2c\x04\0\0", 4) + "WAVEfmt " +
        std::string("\x10\0\0\0\x01\0\x01\0\x40\x1f\0\0\x40\x1f\0\0\x01\0\x08\0", 20) + "data" +
        std::string("\0\x04\0\0", 4) + std::string(1024, '\x80');
    std::ofstream(sound, std::ios::binary) << wav;
  }
  // OpenCV's writer rounds widths to even: an odd-width video written as YUV4MPEG2 (gray).
  const fs::path odd_width = dir / "odd.y4m";
  {
    std::ofstream out(odd_width, std::ios::binary);
    out << "YUV4MPEG2 W63 H48 F25:1 Ip A1:1 Cmono\n";
    for (int i = 0; i < 3; ++i) out << "FRAME\n" << std::string(63 * 48, '\x5a');
  }
  VideoOptions ten;
  ten.max_frames = 10;
  struct Case {
    const char* what;
    std::function<void()> run;
    fs::path file;
    const char* expected;
  };
  const Case cases[] = {
      {"missing", [&] { load_video_gray(dir / "nothing.avi"); }, dir / "nothing.avi",
       "no such file"},
      {"a picture renamed", [&] { load_video_gray(renamed); }, renamed,
       "is not a video but a picture"},
      {"truncated", [&] { load_video_gray(truncated); }, truncated, "truncated or corrupt"},
      {"a truncated sample (OpenCV reads 68 frames without a word)",
       [&] { load_video_gray(test::data_file("samples/tree.avi")); }, "tree.avi",
       "68 frames decode but the file states 444"},
      {"no video stream", [&] { load_video_gray(sound); }, sound, "has no video stream"},
      {"sizes differ", [&] { load_stereo_videos(megamind, test::data_file("samples/vtest.avi")); },
       "vtest.avi", "is 768x576 but"},
      {"odd side-by-side width", [&] { load_side_by_side_video(odd_width); }, odd_width,
       "needs an even width, not 63"},
      {"too many frames", [&] { load_video_gray(megamind, ten); }, megamind,
       "more than 10 frames (max_frames)"},
  };
  for (const Case& c : cases) {
    const std::string error = error_of(c.run);
    EXPECT_NE(error.find(c.expected), std::string::npos) << c.what << ": got '" << error << "'";
    EXPECT_NE(error.find(c.file.filename().string()), std::string::npos) << c.what << ": " << error;
    EXPECT_EQ(error.find('\n'), std::string::npos) << c.what << ": one line";
  }
  // The damaged sample: whatever it gives, an error naming it or frames, never a crash.
  const fs::path bugy = test::data_file("samples/Megamind_bugy.avi");
  VideoOptions all;
  all.max_frames = 2000;
  const std::string error = error_of([&] {
    const std::vector<GrayImage> frames = load_video_gray(bugy, all);
    std::cout << "Megamind_bugy.avi: " << frames.size() << " frames decode, OpenCV reads "
              << opencv_gray_frames(bugy).size() << "\n";
  });
  std::cout << "Megamind_bugy.avi: '" << error << "'\n";
  if (!error.empty()) {
    EXPECT_NE(error.find("Megamind_bugy.avi"), std::string::npos) << error;
  }
}

}  // namespace
}  // namespace epipole::hal
