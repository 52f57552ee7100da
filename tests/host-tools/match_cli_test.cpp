// epipole match as a user runs it: matches on Aloe as JSON and a picture; 3-D points with a
// calibration on the chessboard pair; one-line errors for bad input.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>
#include <string>

#include "../calib/sample_calibration.hpp"
#include "epipole/core/image_io.hpp"
#include "run_tool.hpp"
#include "test_data.hpp"

namespace {

using epipole::test::line_count;
using epipole::test::run_tool;

std::string sample(const char* name) {
  return epipole::test::data_file(std::string("samples/") + name).string();
}

TEST(MatchCli, MatchesAloeAsJsonAndPicture) {
  const std::string picture = ::testing::TempDir() + "epipole-matches.png";
  for (const char* detector : {"fast", "harris"}) {
    const auto r =
        run_tool("match " + sample("aloeL.jpg") + " " + sample("aloeR.jpg") +
                     " --max-disparity 256 --detector " + detector + " --json --draw " + picture,
                 false);
    ASSERT_EQ(r.exit_code, 0) << r.out;
    const auto json = nlohmann::json::parse(r.out);
    EXPECT_EQ(json["width"], 1282);
    EXPECT_EQ(json["detector"], detector);
    EXPECT_FALSE(json["rectified"].get<bool>());
    EXPECT_TRUE(json["points"].is_null()) << "no 3-D points without --calib";
    EXPECT_NE(json["points_note"].get<std::string>().find("--calib"), std::string::npos);
    const auto& matches = json["matches"];
    ASSERT_GT(matches.size(), 200u) << detector;
    // Aloe's disparities are 43..211 px: most matches are in that range.
    std::size_t in_range = 0;
    for (const auto& m : matches) {
      const double d = m["disparity"].get<double>();
      EXPECT_NEAR(m["xl"].get<double>() - m["xr"].get<double>(), d, 1e-3);
      in_range += d >= 40 && d <= 215 ? 1 : 0;
    }
    EXPECT_GT(in_range, matches.size() * 9 / 10) << detector;
    const auto image = epipole::load_gray(picture);
    EXPECT_EQ(image.width(), 2 * 1282) << "left and right side by side";
  }
  const auto text =
      run_tool("match " + sample("aloeL.jpg") + " " + sample("aloeR.jpg") + " -d 256");
  EXPECT_EQ(text.exit_code, 0) << text.out;
  EXPECT_EQ(line_count(text.out), 1) << text.out;
  EXPECT_NE(text.out.find("no 3-D points without --calib"), std::string::npos) << text.out;
}

TEST(MatchCli, PointsWithACalibration) {
  const std::string rig = ::testing::TempDir() + "epipole-match-rig.yaml";
  epipole::calib::save_calibration(rig, epipole::test::sample_calibration());
  const auto r = run_tool("match " + sample("left01.jpg") + " " + sample("right01.jpg") +
                              " --calib " + rig + " --detector harris -d 128 --json",
                          false);
  ASSERT_EQ(r.exit_code, 0) << r.out;
  const auto json = nlohmann::json::parse(r.out);
  EXPECT_TRUE(json["rectified"].get<bool>());
  const auto& points = json["points"];
  ASSERT_GT(points.size(), 20u) << r.out;
  EXPECT_LE(points.size(), json["matches"].size());
  // The chessboard is 0.3..0.5 m from the cameras; the scene behind it farther.
  std::size_t board = 0;
  for (const auto& p : points) {
    const double z = p["z"].get<double>();
    EXPECT_GT(z, 0.0);
    board += z > 0.3 && z < 0.5 ? 1 : 0;
  }
  EXPECT_GT(board, 10u);
}

TEST(MatchCli, BadInputIsOneLine) {
  const auto sizes = run_tool("match " + sample("left01.jpg") + " " + sample("aloeR.jpg"));
  EXPECT_EQ(sizes.exit_code, 1) << sizes.out;
  EXPECT_EQ(line_count(sizes.out), 1) << sizes.out;
  EXPECT_NE(sizes.out.find("a stereo pair must have one size"), std::string::npos) << sizes.out;
  const auto range =
      run_tool("match " + sample("left01.jpg") + " " + sample("right01.jpg") + " -d 640");
  EXPECT_EQ(range.exit_code, 1) << range.out;
  EXPECT_EQ(line_count(range.out), 1) << range.out;
  EXPECT_NE(range.out.find("disparity range 640"), std::string::npos) << range.out;
  const auto ratio =
      run_tool("match " + sample("left01.jpg") + " " + sample("right01.jpg") + " --ratio 0");
  EXPECT_EQ(ratio.exit_code, 1) << ratio.out;
  EXPECT_NE(ratio.out.find("ratio 0"), std::string::npos) << ratio.out;
  const std::string rig = ::testing::TempDir() + "epipole-match-rig2.yaml";
  epipole::calib::save_calibration(rig, epipole::test::sample_calibration());
  const auto wrong =
      run_tool("match " + sample("aloeL.jpg") + " " + sample("aloeR.jpg") + " --calib " + rig);
  EXPECT_EQ(wrong.exit_code, 1) << wrong.out;
  EXPECT_NE(wrong.out.find("is a calibration for 640x480"), std::string::npos) << wrong.out;
}

}  // namespace
