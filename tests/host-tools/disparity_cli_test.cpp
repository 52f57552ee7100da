// epipole disparity as a user runs it: the 16-bit PNG and colour picture on Aloe, JSON, and
// one-line errors for bad input.
#include <gtest/gtest.h>

#include <sys/wait.h>
#include <algorithm>
#include <array>
#include <cstdio>
#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <set>
#include <string>

#include "epipole/core/image_io.hpp"
#include "run_tool.hpp"
#include "test_data.hpp"

namespace {

using Result = epipole::test::ToolResult;
using epipole::test::line_count;
using epipole::test::run_tool;

std::string aloe(const char* name) {
  return epipole::test::data_file(name).string();
}

// The colour picture: the disparity on a blue (far) to red (near) map (Aloe: 43..211 px of the
// 224; TURBO is blue below 60 and red above 140), invalid pixels black, over a legend (title and
// tick labels in white, the colour bar).
void expect_colour_picture(const std::string& file, const epipole::Image<std::uint16_t>& png) {
  const cv::Mat bgr = cv::imread(file, cv::IMREAD_COLOR);
  ASSERT_FALSE(bgr.empty()) << file;
  ASSERT_EQ(bgr.cols, png.width());
  ASSERT_GT(bgr.rows, png.height()) << "the legend is below the picture";
  long dark_zero = 0, zero = 0, red_near = 0, near = 0, blue_far = 0, far = 0;
  for (int y = 0; y < png.height(); ++y) {
    for (int x = 0; x < png.width(); ++x) {
      const cv::Vec3b p = bgr.at<cv::Vec3b>(y, x);
      const int d = png(x, y) / 16;
      if (png(x, y) == 0) {  // invalid (black) or 0 (the map's darkest blue)
        ++zero;
        dark_zero += std::max({p[0], p[1], p[2]}) < 64 ? 1 : 0;
      } else if (d >= 140) {
        ++near;
        red_near += p[2] > p[0] + 64 ? 1 : 0;
      } else if (d >= 40 && d <= 60) {
        ++far;
        blue_far += p[0] > p[2] + 64 ? 1 : 0;
      }
    }
  }
  EXPECT_EQ(dark_zero, zero);
  ASSERT_GT(near, 1000);
  ASSERT_GT(far, 1000);
  EXPECT_EQ(red_near, near);
  EXPECT_EQ(blue_far, far);
  const cv::Mat legend = bgr.rowRange(png.height(), bgr.rows);
  cv::Mat white;
  cv::inRange(legend, cv::Scalar::all(200), cv::Scalar::all(255), white);
  EXPECT_GT(cv::countNonZero(white), 100) << "the legend's title and labels";
  std::set<int> bar_colours;
  for (int y = 0; y < legend.rows; ++y) {
    for (int x = 0; x < legend.cols; ++x) {
      const cv::Vec3b p = legend.at<cv::Vec3b>(y, x);
      if (p[0] != p[1] || p[1] != p[2]) bar_colours.insert(p[0] << 16 | p[1] << 8 | p[2]);
    }
  }
  EXPECT_GT(bar_colours.size(), 200u) << "the colour bar";
}

TEST(DisparityCli, WritesDisparityPngAndColourPicture) {
  const std::string out = ::testing::TempDir() + "epipole-disparity.png";
  const std::string colour = ::testing::TempDir() + "epipole-disparity-colour.png";
  for (const char* method : {"sgm", "bm"}) {
    const Result r = run_tool("disparity " + aloe("samples/aloeL.jpg") + " " +
                                  aloe("samples/aloeR.jpg") + " --max-disparity 224 --method " +
                                  method + " --out " + out + " --color " + colour + " --json",
                              false);
    ASSERT_EQ(r.exit_code, 0) << r.out;
    const auto json = nlohmann::json::parse(r.out);
    EXPECT_EQ(json["width"], 1282);
    EXPECT_EQ(json["height"], 1110);
    EXPECT_EQ(json["method"], method);
    EXPECT_GT(json["density"].get<double>(), 0.5);
    const auto png = epipole::load_gray16(out);
    ASSERT_EQ(png.width(), 1282);
    ASSERT_EQ(png.height(), 1110);
    // Aloe's disparities are 43..211 px: most valid pixels are in that range, x16.
    long valid = 0, in_range = 0;
    for (int y = 0; y < png.height(); ++y) {
      for (int x = 0; x < png.width(); ++x) {
        const int v = png(x, y);
        if (v == 0) continue;
        ++valid;
        in_range += v >= 40 * 16 && v <= 215 * 16 ? 1 : 0;
      }
    }
    EXPECT_GT(in_range, valid * 9 / 10) << method;
    expect_colour_picture(colour, png);
  }
}

// --confidence: 0 exactly where the disparity is invalid, or filled by --hole-fill or
// --fill-occlusions (made up, not measured); a value for every measured pixel, smoothed by
// --spatial or not. Counted right of the first 224 columns: the PNG's 0 means invalid, and nearer
// the left border a valid disparity can be 0 too.
TEST(DisparityCli, WritesTheConfidenceOfEveryMeasuredPixel) {
  const std::string out = ::testing::TempDir() + "epipole-disparity-c.png";
  const std::string confidence = ::testing::TempDir() + "epipole-confidence.png";
  const auto run = [&](const std::string& extra) {
    const Result r = run_tool("disparity " + aloe("samples/aloeL.jpg") + " " +
                                  aloe("samples/aloeR.jpg") + " --max-disparity 224 --out " + out +
                                  " --confidence " + confidence + " --json" + extra,
                              false);
    EXPECT_EQ(r.exit_code, 0) << r.out;
    EXPECT_EQ(nlohmann::json::parse(r.out)["confidence"], confidence);
  };
  for (const std::string filters : {"", " --spatial 50", " --hole-fill 64", " --fill-occlusions"}) {
    SCOPED_TRACE(filters);
    run(filters);
    const auto disparity = epipole::load_gray16(out);
    const auto trust = epipole::load_gray(confidence);
    ASSERT_EQ(trust.width(), disparity.width());
    ASSERT_EQ(trust.height(), disparity.height());
    long valid = 0, trusted = 0, invalid_with_confidence = 0;
    for (int y = 0; y < trust.height(); ++y) {
      for (int x = 224; x < trust.width(); ++x) {
        valid += disparity(x, y) != 0 ? 1 : 0;
        trusted += trust(x, y) != 0 ? 1 : 0;
        invalid_with_confidence += disparity(x, y) == 0 && trust(x, y) != 0 ? 1 : 0;
      }
    }
    EXPECT_EQ(invalid_with_confidence, 0);
    EXPECT_GT(trusted, valid / 2);
    if (filters.find("fill") == std::string::npos) {
      EXPECT_EQ(trusted, valid) << "every measured pixel has a confidence";
    } else {
      EXPECT_LT(trusted, valid) << "the filled pixels have none";
    }
  }
}

TEST(DisparityCli, TextSummary) {
  const std::string out = ::testing::TempDir() + "epipole-disparity-text.png";
  const Result r = run_tool("disparity " + aloe("samples/aloeL.jpg") + " " +
                            aloe("samples/aloeR.jpg") + " -d 256 --method bm --out " + out);
  EXPECT_EQ(r.exit_code, 0) << r.out;
  EXPECT_EQ(line_count(r.out), 1) << r.out;
  EXPECT_NE(r.out.find("% valid"), std::string::npos) << r.out;
}

TEST(DisparityCli, BadInputIsAOneLineError) {
  const std::string left = aloe("samples/aloeL.jpg");
  const std::string right = aloe("samples/aloeR.jpg");
  const std::string other = aloe("samples/left01.jpg");
  const std::string out = ::testing::TempDir() + "epipole-disparity-bad.png";
  const struct {
    std::string arguments;
    std::string message;
  } cases[] = {
      {"disparity " + left + " " + other + " --out " + out, "must have one size"},
      {"disparity " + left + " " + right + " -d 40 --out " + out, "multiple of 16"},
      {"disparity " + left + " " + right + " -d 512 --out " + out, "multiple of 16"},
      {"disparity " + left + " " + right + " --method xyz --out " + out, "method"},
      {"disparity " + left + " " + right + " --spatial 100 --out " + out, "--spatial"},
      {"disparity " + left + " /no/such/file.png --out " + out, "file.png"},
      {"disparity " + left + " " + right, "--out"},
  };
  for (const auto& c : cases) {
    const Result r = run_tool(c.arguments);
    EXPECT_NE(r.exit_code, 0) << c.arguments;
    EXPECT_GE(line_count(r.out), 1) << c.arguments;
    EXPECT_NE(r.out.find(c.message), std::string::npos) << c.arguments << "\n" << r.out;
  }
}

TEST(DisparityCli, RangeWiderThanTheImage) {
  // A 64-pixel-wide crop cannot hold 64 disparities.
  const std::string out = ::testing::TempDir() + "epipole-disparity-narrow.png";
  const std::string narrow = ::testing::TempDir() + "epipole-narrow.pgm";
  epipole::GrayImage image(64, 48);
  for (int y = 0; y < 48; ++y) {
    for (int x = 0; x < 64; ++x) image(x, y) = static_cast<std::uint8_t>(x * 4 + y);
  }
  epipole::save_image(narrow, epipole::GrayView(image.view()));
  const Result r = run_tool("disparity " + narrow + " " + narrow + " -d 64 --out " + out);
  EXPECT_EQ(r.exit_code, 1) << r.out;
  EXPECT_EQ(line_count(r.out), 1) << r.out;
  EXPECT_NE(r.out.find("not smaller than the image width 64"), std::string::npos) << r.out;
}

TEST(DisparityCli, RectifiesWithACalibration) {
  const std::string samples = epipole::test::data_file("samples/left01.jpg").parent_path().string();
  const std::string rig = ::testing::TempDir() + "epipole-disparity-rig.yaml";
  const Result calibrated =
      run_tool("calibrate --left '" + samples + "/left[0-9]*.jpg' --right '" + samples +
               "/right[0-9]*.jpg' --board chessboard:9x6 " + "--square 0.025 -o " + rig);
  ASSERT_EQ(calibrated.exit_code, 0) << calibrated.out;
  const std::string out = ::testing::TempDir() + "epipole-disparity-rectified.png";
  const Result r = run_tool("disparity " + samples + "/left01.jpg " + samples +
                                "/right01.jpg --calib " + rig + " -d 64 --out " + out + " --json",
                            false);
  ASSERT_EQ(r.exit_code, 0) << r.out;
  const auto json = nlohmann::json::parse(r.out);
  EXPECT_TRUE(json["rectified"].get<bool>());
  EXPECT_EQ(json["width"], 640);
  EXPECT_GT(json["density"].get<double>(), 0.1);
  const Result wrong_size =
      run_tool("disparity " + aloe("samples/aloeL.jpg") + " " + aloe("samples/aloeR.jpg") +
               " --calib " + rig + " --out " + out);
  EXPECT_EQ(wrong_size.exit_code, 1) << wrong_size.out;
  EXPECT_EQ(line_count(wrong_size.out), 1) << wrong_size.out;
  EXPECT_NE(wrong_size.out.find("is a calibration for 640x480"), std::string::npos)
      << wrong_size.out;
}

// A 4x2 scene whose every figure is known: truth 40 px (two pixels unknown), the disparity off
// by 0, 1.5, 2.5 and 5 px, one pixel missing; the mask marks the top row non-occluded.
struct HandMade {
  std::string disparity = ::testing::TempDir() + "epipole-eval-disparity.png";
  std::string truth = ::testing::TempDir() + "epipole-eval-truth.png";
  std::string mask = ::testing::TempDir() + "epipole-eval-mask.png";
  HandMade() {
    epipole::Image<std::uint16_t> d(4, 2);
    epipole::GrayImage t(4, 2);
    epipole::GrayImage m(4, 2);
    const double off[8] = {0, 1.5, 2.5, 5, 0, 0, 0, 0};
    for (int i = 0; i < 8; ++i) {
      const int x = i % 4, y = i / 4;
      d(x, y) = static_cast<std::uint16_t>((40 + off[i]) * 16);
      t(x, y) = 40;
      m(x, y) = y == 0 ? 255 : 128;
    }
    d(0, 1) = 0;  // missing
    t(2, 1) = 0;  // unknown
    t(3, 1) = 0;
    epipole::save_image(disparity, epipole::ImageView<const std::uint16_t>(d.view()));
    epipole::save_image(truth, epipole::ImageView<const std::uint8_t>(t.view()));
    epipole::save_image(mask, epipole::ImageView<const std::uint8_t>(m.view()));
  }
};

TEST(EvalDisparityCli, EveryFigureOnAHandMadeMapAllAndNonOccluded) {
  const HandMade files;
  const Result r = run_tool(
      "eval-disparity " + files.disparity + " " + files.truth + " --mask " + files.mask + " --json",
      false);
  ASSERT_EQ(r.exit_code, 0) << r.out;
  const auto j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j["width"], 4);
  // All: 6 pixels with truth (errors 0, 1.5, 2.5, 5, missing, 0).
  const auto& all = j["all"];
  EXPECT_EQ(all["pixels"], 6);
  EXPECT_EQ(all["valid"], 5);
  EXPECT_DOUBLE_EQ(all["bad1"].get<double>(), 4.0 / 6);
  EXPECT_DOUBLE_EQ(all["bad2"].get<double>(), 3.0 / 6);
  EXPECT_DOUBLE_EQ(all["bad4"].get<double>(), 2.0 / 6);
  EXPECT_DOUBLE_EQ(all["d1"].get<double>(), 2.0 / 6);  // 5 px (> 3 and > 2) and the missing
  EXPECT_DOUBLE_EQ(all["density"].get<double>(), 5.0 / 6);
  EXPECT_DOUBLE_EQ(all["mean_error_px"].get<double>(), 9.0 / 5);
  // Non-occluded: the top row only.
  const auto& noc = j["nonoccluded"];
  EXPECT_EQ(noc["pixels"], 4);
  EXPECT_DOUBLE_EQ(noc["bad2"].get<double>(), 2.0 / 4);
  EXPECT_DOUBLE_EQ(noc["density"].get<double>(), 1.0);
  // The table says the same.
  const Result table =
      run_tool("eval-disparity " + files.disparity + " " + files.truth + " --mask " + files.mask);
  ASSERT_EQ(table.exit_code, 0) << table.out;
  EXPECT_NE(table.out.find("all             66.67 %  50.00 %  33.33 %  33.33 %   83.33 %"),
            std::string::npos)
      << table.out;
  EXPECT_NE(table.out.find("non-occluded"), std::string::npos) << table.out;
}

TEST(EvalDisparityCli, AloeFromTheDisparityCommandAgainstItsGroundTruth) {
  const std::string out = ::testing::TempDir() + "epipole-eval-aloe.png";
  const Result made = run_tool("disparity " + aloe("samples/aloeL.jpg") + " " +
                               aloe("samples/aloeR.jpg") + " -d 224 --out " + out);
  ASSERT_EQ(made.exit_code, 0) << made.out;
  const Result r =
      run_tool("eval-disparity " + out + " " + aloe("samples/aloeGT.png") + " --json", false);
  ASSERT_EQ(r.exit_code, 0) << r.out;
  const auto all = nlohmann::json::parse(r.out)["all"];
  // Middlebury's 8-bit truth read as disparities in pixels: the quality mode's figures
  // (docs/vision.md: bad2 24 %, density near 80 %), not those of a misread scale.
  EXPECT_GT(all["pixels"].get<long>(), 1'000'000);
  EXPECT_LT(all["bad2"].get<double>(), 0.30);
  EXPECT_GT(all["density"].get<double>(), 0.70);
  EXPECT_LT(all["mean_error_px"].get<double>(), 2.0);
}

TEST(EvalDisparityCli, BadInputIsAOneLineError) {
  const HandMade files;
  const std::string aloe_truth = aloe("samples/aloeGT.png");
  const std::string empty_truth = ::testing::TempDir() + "epipole-eval-empty.png";
  epipole::GrayImage unknown(4, 2);  // an image's pixels start undefined: all set to 0 here
  for (int y = 0; y < 2; ++y) {
    for (int x = 0; x < 4; ++x) unknown(x, y) = 0;
  }
  epipole::save_image(empty_truth, epipole::ImageView<const std::uint8_t>(unknown.view()));
  const struct {
    std::string arguments;
    int exit_code;
    std::string message;
  } cases[] = {
      {"eval-disparity " + files.disparity + " " + aloe_truth, 1, "is 4x2 but"},
      {"eval-disparity " + files.disparity + " " + files.truth + " --mask " + aloe_truth, 1,
       "is 1282x1110 but"},
      {"eval-disparity " + files.disparity + " " + empty_truth, 1, "no pixel with ground truth"},
      {"eval-disparity " + files.disparity + " " + files.truth + " --disparity-scale 0.5", 2,
       "disparity-scale"},
      {"eval-disparity " + files.disparity + " /no/such/truth.png", 2, "truth.png"},
      {"eval-disparity " + files.disparity + " " + files.truth + " --truth-scale 0", 2,
       "truth-scale"},
  };
  for (const auto& c : cases) {
    const Result r = run_tool(c.arguments);
    EXPECT_EQ(r.exit_code, c.exit_code) << c.arguments << "\n" << r.out;
    EXPECT_NE(r.out.find(c.message), std::string::npos) << c.arguments << "\n" << r.out;
  }
}

}  // namespace
