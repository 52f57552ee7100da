// epipole bench as a user runs it: the firmware's stages and OpenCV's on the simulated board's
// Aloe scene and on a board given images, as JSON and as a table, and one-line errors. Timings
// are only checked to be there (measured, positive, p99 not below p50), never against a bound.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdlib>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>

#include "run_tool.hpp"
#include "test_data.hpp"
#include "test_paths.hpp"

namespace {

// OpenCV's parallel loops run on TBB, whose worker threads are still alive when the tool exits;
// LeakSanitizer's check at exit then now and again crashes in its own tracer ("LeakSanitizer has
// encountered a fatal error", exit 134) in the host-asan preset. The bench's processes run
// without that check (AddressSanitizer's other checks stay on); the code they run is leak-checked
// by the in-process tests of the same libraries. The other tools' tests in this program keep it.
class BenchCli : public ::testing::Test {
 protected:
  void SetUp() override {
    const char* options = std::getenv("ASAN_OPTIONS");
    saved_ = options != nullptr ? std::optional<std::string>(options) : std::nullopt;
    const std::string value = saved_.value_or("") + (saved_ ? ":" : "") + "detect_leaks=0";
    ::setenv("ASAN_OPTIONS", value.c_str(), 1);
  }
  void TearDown() override {
    if (saved_) {
      ::setenv("ASAN_OPTIONS", saved_->c_str(), 1);
    } else {
      ::unsetenv("ASAN_OPTIONS");
    }
  }

 private:
  std::optional<std::string> saved_;
};

using epipole::test::line_count;
using epipole::test::run_tool;

std::string board(const char* name) {
  return "--board '" + std::string(epipole::test::source_dir()) + "/board/" + name + "'";
}

void expect_timing(const nlohmann::json& t, const std::string& what) {
  EXPECT_GT(t["p50_ms"].get<double>(), 0.0) << what;
  EXPECT_GE(t["p99_ms"].get<double>(), t["p50_ms"].get<double>()) << what;
  EXPECT_GT(t["mean_ms"].get<double>(), 0.0) << what;
}

TEST_F(BenchCli, EveryStageOfBothSidesForEachThreadCount) {
  const auto r = run_tool(
      "bench " + board("sim") + " --scene aloe -n 3 --warmup 1 --threads 1,2 --json", false);
  ASSERT_EQ(r.exit_code, 0) << r.out;
  const auto b = nlohmann::json::parse(r.out);
  EXPECT_EQ(b["board"], "sim");
  EXPECT_EQ(b["images"], "scene aloe");
  EXPECT_EQ(b["width"], 640);
  EXPECT_EQ(b["max_disparity"], 128);
  EXPECT_EQ(b["pairs"], 3);
  ASSERT_EQ(b["runs"].size(), 2u);
  for (int i = 0; i < 2; ++i) {
    const auto& run = b["runs"][i];
    EXPECT_EQ(run["threads"], i + 1);
    for (const char* stage : {"rectify", "corners", "disparity", "sparse", "detect"}) {
      ASSERT_TRUE(run["epipole"]["stages"].contains(stage)) << stage << "\n" << r.out;
      expect_timing(run["epipole"]["stages"][stage], std::string("epipole ") + stage);
    }
    for (const char* stage : {"rectify", "corners", "disparity", "detect"}) {
      ASSERT_TRUE(run["opencv"]["stages"].contains(stage)) << stage << "\n" << r.out;
      expect_timing(run["opencv"]["stages"][stage], std::string("opencv ") + stage);
    }
    EXPECT_FALSE(run["opencv"]["stages"].contains("sparse")) << "OpenCV has no sparse matcher";
    expect_timing(run["epipole"]["pair"], "epipole pair");
    expect_timing(run["opencv"]["pair"], "opencv pair");
    // A pair takes at least as long as its longest stage; on one thread, as all of them (with
    // more, the stages share the threads), but for its rectification, which was done ahead in
    // the time of the pair before (b["rectify_ahead"]).
    EXPECT_TRUE(b["rectify_ahead"].get<bool>());
    double sum = 0;
    double longest = 0;
    for (const auto& [name, t] : run["epipole"]["stages"].items()) {
      if (name == "rectify") continue;
      sum += t["mean_ms"].get<double>();
      longest = std::max(longest, t["mean_ms"].get<double>());
    }
    const double pair = run["epipole"]["pair"]["mean_ms"].get<double>();
    EXPECT_GE(pair, longest * 0.999);
    if (i == 0) {
      EXPECT_GE(pair, sum * 0.999);
    }
    EXPECT_GT(run["epipole"]["pairs_per_second"].get<double>(), 0.0);
    EXPECT_GT(run["opencv"]["pairs_per_second"].get<double>(), 0.0);
  }
  EXPECT_NE(b["notes"].dump().find("sparse"), std::string::npos) << b["notes"];
  // The same pairs give the same results at every thread count (and OpenCV's side, which ran
  // between them, has not touched the images).
  const auto& found = b["runs"][0]["epipole"]["found"];
  EXPECT_GT(found["corners"].get<int>(), 0);
  EXPECT_GT(found["matches"].get<int>(), 0);
  EXPECT_EQ(b["runs"][1]["epipole"]["found"], found);
}

TEST_F(BenchCli, TableAndImagesForABoardWithoutScenes) {
  const auto table =
      run_tool("bench " + board("sim") + " --scene aloe -n 1 --warmup 0 --threads 1");
  ASSERT_EQ(table.exit_code, 0) << table.out;
  for (const char* text :
       {"1 thread", "rectify", "disparity", "detect", "pair", "pairs/s", "opencv/epipole"}) {
    EXPECT_NE(table.out.find(text), std::string::npos) << text << "\n" << table.out;
  }
  const std::string left = epipole::test::data_file("samples/aloeL.jpg").string();
  const std::string right = epipole::test::data_file("samples/aloeR.jpg").string();
  const auto usb = run_tool("bench " + board("usb-stereo") + " --left '" + left + "' --right '" +
                                right + "' -n 1 --warmup 0 --threads 1 --no-opencv --json",
                            false);
  ASSERT_EQ(usb.exit_code, 0) << usb.out;
  const auto b = nlohmann::json::parse(usb.out);
  EXPECT_EQ(b["board"], "usb-stereo");
  EXPECT_NE(b["images"].get<std::string>().find("aloeL.jpg"), std::string::npos);
  ASSERT_EQ(b["runs"].size(), 1u);
  EXPECT_FALSE(b["runs"][0].contains("opencv"));
  EXPECT_TRUE(b["runs"][0]["epipole"]["stages"].contains("disparity"));
}

// A correction's map rebuild, beside each pair or after it: timed apart, the pairs' times beside.
TEST_F(BenchCli, AMapRebuiltBesideOrAfterEachPairIsTimedApart) {
  for (const std::string mode : {"beside", "after"}) {
    const auto r = run_tool("bench " + board("sim") +
                            " --scene faces --stages rectify -n 2 --warmup 0 --threads 1 "
                            "--no-opencv --json --rebuild-map " +
                            mode);
    ASSERT_EQ(r.exit_code, 0) << r.out;
    const auto run = nlohmann::json::parse(r.out)["runs"][0];
    ASSERT_TRUE(run.contains("epipole_rebuilding")) << run.dump(2);
    const auto& with = run["epipole_rebuilding"];
    EXPECT_EQ(with["rebuild_map"], mode);
    EXPECT_GT(with["map_rebuild"]["p50_ms"].get<double>(), 0) << with.dump(2);
    EXPECT_GT(with["pair"]["p50_ms"].get<double>(), 0);
    EXPECT_TRUE(with["stages"].contains("rectify"));
    EXPECT_FALSE(run["epipole"].contains("map_rebuild")) << "only the run with it";
  }
  const auto table = run_tool("bench " + board("sim") +
                              " --scene faces --stages rectify -n 1 --warmup 0 --threads 1 "
                              "--no-opencv --rebuild-map after");
  ASSERT_EQ(table.exit_code, 0) << table.out;
  EXPECT_NE(table.out.find("a map rebuilt after each pair"), std::string::npos) << table.out;
}

TEST_F(BenchCli, BadArgumentsAreUsageErrorsAndBadInputOneLine) {
  for (const std::string& args :
       {std::string("--threads 0"), std::string("--threads 1,x"), std::string("-n 0"),
        std::string("--rebuild-map sideways"), std::string("--left nowhere.png"),
        std::string("--left nowhere.png --right nowhere.png")}) {
    const auto r = run_tool("bench " + board("sim") + " " + args);
    EXPECT_EQ(r.exit_code, 2) << args << "\n" << r.out;
  }
  const auto no_scenes = run_tool("bench " + board("usb-stereo") + " -n 1");
  EXPECT_EQ(no_scenes.exit_code, 1) << no_scenes.out;
  EXPECT_EQ(line_count(no_scenes.out), 1) << no_scenes.out;
  EXPECT_NE(no_scenes.out.find("--left and --right"), std::string::npos) << no_scenes.out;
  const auto no_scene = run_tool("bench " + board("sim") + " --scene nosuch -n 1");
  EXPECT_EQ(no_scene.exit_code, 1) << no_scene.out;
  EXPECT_NE(no_scene.out.find(
                "'nosuch' is not a scene of this board (chessboard, aloe, faces, ground, loop)"),
            std::string::npos)
      << no_scene.out;
}

}  // namespace
