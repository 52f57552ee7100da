// The epipole tool as a user runs it: exit codes, one-line errors, JSON on real images.
#include <gtest/gtest.h>

#include <sys/wait.h>
#include <array>
#include <cstdio>
#include <nlohmann/json.hpp>
#include <string>

#include "run_tool.hpp"
#include "test_data.hpp"

namespace {

using Result = epipole::test::ToolResult;
using epipole::test::line_count;
using epipole::test::run_tool;

TEST(Cli, HelpAndVersion) {
  const Result help = run_tool("--help");
  EXPECT_EQ(help.exit_code, 0);
  EXPECT_NE(help.out.find("features"), std::string::npos) << help.out;
  const Result features_help = run_tool("features --help");
  EXPECT_EQ(features_help.exit_code, 0);
  EXPECT_NE(features_help.out.find("--threshold"), std::string::npos) << features_help.out;
  for (const char* command :
       {"--help", "features --help", "sim --help", "calibrate --help", "eval-disparity --help"}) {
    const Result r = run_tool(command);
    EXPECT_NE(r.out.find("Exit status: 0 success, 1 failure"), std::string::npos) << r.out;
  }
  const Result version = run_tool("--version");
  EXPECT_EQ(version.exit_code, 0);
  EXPECT_EQ(version.out.rfind("epipole ", 0), 0u) << version.out;
}

// Exit status 2: the command line is wrong; 1: it is right but the work failed.
TEST(Cli, BadArgumentsFailWithOneLine) {
  for (const char* arguments :
       {"", "no-such-command", "features", "features --threshold 300 x.png",
        "--kernels avx features x.png", "features -n 5 x.png", "sim --frames x"}) {
    const Result r = run_tool(arguments);
    EXPECT_EQ(r.exit_code, 2) << arguments << "\n" << r.out;
    EXPECT_GE(line_count(r.out), 1) << arguments;
  }
  const Result missing = run_tool("features /no/such/file.png");
  EXPECT_EQ(missing.exit_code, 2) << "an input that is not there: the argument is wrong\n"
                                  << missing.out;
  EXPECT_NE(missing.out.find("/no/such/file.png"), std::string::npos) << missing.out;
}

// One meaning per short flag: -c at most this many corners, -n stop after this many, -o the
// output, -t the FAST threshold, -d the disparities searched.
TEST(Cli, ShortFlagsMeanOneThing) {
  const std::string image = epipole::test::data_file("samples/left01.jpg").string();
  const Result corners = run_tool("features '" + image + "' -c 7 -t 30 --json");
  ASSERT_EQ(corners.exit_code, 0) << corners.out;
  EXPECT_EQ(nlohmann::json::parse(corners.out)["keypoints"].size(), 7u);
  const Result long_name = run_tool("features '" + image + "' --max 7 --json");
  ASSERT_EQ(long_name.exit_code, 0) << long_name.out;
  EXPECT_EQ(nlohmann::json::parse(long_name.out)["keypoints"].size(), 7u) << "--max still works";
  for (const char* help : {"features --help", "match --help"}) {
    const Result r = run_tool(help);
    EXPECT_NE(r.out.find("-c,"), std::string::npos) << r.out;
    EXPECT_EQ(r.out.find("-n,"), std::string::npos) << r.out;
  }
  for (const char* help : {"link --help", "sim --help"}) {
    EXPECT_NE(run_tool(help).out.find("-n,"), std::string::npos) << help;
  }
}

TEST(Cli, CorruptImageIsAOneLineError) {
  const std::string path = ::testing::TempDir() + "epipole-cli-corrupt.png";
  FILE* f = std::fopen(path.c_str(), "wb");
  std::fputs("not a png", f);
  std::fclose(f);
  const Result r = run_tool("features " + path);
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_EQ(line_count(r.out), 1) << r.out;
  EXPECT_NE(r.out.find(path), std::string::npos) << r.out;
  std::remove(path.c_str());
}

TEST(Cli, FeaturesJsonOnARealImage) {
  const std::string image = epipole::test::data_file("samples/left01.jpg").string();
  const std::string picture = ::testing::TempDir() + "epipole-cli-corners.png";
  const Result r =
      run_tool("features " + image + " --threshold 20 --json --draw " + picture, false);
  ASSERT_EQ(r.exit_code, 0) << r.out;
  const auto json = nlohmann::json::parse(r.out);
  EXPECT_EQ(json["width"], 640);
  EXPECT_EQ(json["height"], 480);
  const auto& keypoints = json["keypoints"];
  ASSERT_GT(keypoints.size(), 100u);
  for (const auto& k : keypoints) {
    EXPECT_GE(k["score"].get<double>(), 20.0);
    EXPECT_GE(k["x"].get<int>(), 3);
    EXPECT_LT(k["x"].get<int>(), 640 - 3);
  }
  // Both kernel paths print the same corners.
  const Result ref = run_tool("--kernels ref features " + image + " --threshold 20 --json", false);
  ASSERT_EQ(ref.exit_code, 0);
  EXPECT_EQ(nlohmann::json::parse(ref.out)["keypoints"], keypoints);
  FILE* drawn = std::fopen(picture.c_str(), "rb");
  ASSERT_NE(drawn, nullptr) << "no picture written";
  std::fclose(drawn);
  std::remove(picture.c_str());
}

TEST(Cli, HarrisFeaturesJsonOnARealImage) {
  const std::string image = epipole::test::data_file("samples/left01.jpg").string();
  const std::string options =
      " --detector harris --quality 0.01 --min-distance 10 --block-size 3 "
      "--k 0.04 --max 200 --json";
  const Result r = run_tool("features " + image + options, false);
  ASSERT_EQ(r.exit_code, 0) << r.out;
  const auto json = nlohmann::json::parse(r.out);
  EXPECT_EQ(json["detector"], "harris");
  EXPECT_EQ(json["width"], 640);
  EXPECT_EQ(json["height"], 480);
  EXPECT_EQ(json["block_size"], 3);
  EXPECT_DOUBLE_EQ(json["quality"].get<double>(), 0.01);
  EXPECT_DOUBLE_EQ(json["min_distance"].get<double>(), 10.0);
  EXPECT_DOUBLE_EQ(json["k"].get<double>(), 0.04);
  const auto& keypoints = json["keypoints"];
  ASSERT_GT(keypoints.size(), 100u);
  ASSERT_LE(keypoints.size(), 200u);
  // Strongest first, all above the quality threshold, inside the border, 10 pixels apart.
  const double strongest = keypoints[0]["score"].get<double>();
  for (std::size_t i = 0; i < keypoints.size(); ++i) {
    const auto& k = keypoints[i];
    EXPECT_GT(k["score"].get<double>(), 0.01 * strongest * (1 - 1e-6));
    if (i > 0) {
      EXPECT_LE(k["score"].get<double>(), keypoints[i - 1]["score"].get<double>());
    }
    EXPECT_GE(k["x"].get<int>(), 1);
    EXPECT_LT(k["x"].get<int>(), 640 - 1);
    EXPECT_GE(k["y"].get<int>(), 1);
    EXPECT_LT(k["y"].get<int>(), 480 - 1);
    for (std::size_t j = 0; j < i; ++j) {
      const int dx = k["x"].get<int>() - keypoints[j]["x"].get<int>();
      const int dy = k["y"].get<int>() - keypoints[j]["y"].get<int>();
      EXPECT_GE(dx * dx + dy * dy, 100) << i << " and " << j;
    }
  }
  // Both kernel paths print the same corners; a bad block size is a one-line error.
  const Result ref = run_tool("--kernels ref features " + image + options, false);
  ASSERT_EQ(ref.exit_code, 0);
  EXPECT_EQ(nlohmann::json::parse(ref.out)["keypoints"], keypoints);
  const Result even = run_tool("features " + image + " --detector harris --block-size 4");
  EXPECT_EQ(even.exit_code, 1) << even.out;
  EXPECT_EQ(line_count(even.out), 1) << even.out;
  EXPECT_NE(even.out.find("block_size"), std::string::npos) << even.out;
}

}  // namespace
