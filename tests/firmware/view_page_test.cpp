// The live view's page as a browser takes it: the firmware on the simulated board serves the page
// and its /api/ over HTTP on the loopback interface. The pictures decode (OpenCV's decoder) to
// the pipeline's rectified image and the disparity's colours; health and the pair are JSON; what
// is not served is a 4xx. Headless Chromium (Debian's) loads the page: its screenshot shows the
// pictures in colour, and the health it shows changes between two loads.
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <string>
#include <thread>

#include "epipole/firmware/firmware.hpp"
#include "loopback.hpp"
#include "ros_message_checks.hpp"
#include "run_tool.hpp"
#include "sim_rig.hpp"
#include "test_paths.hpp"
#include "view/disparity_colours.hpp"

namespace epipole::firmware {
namespace {

using test::http_request;
using test::HttpResponse;

// `path` once it answers 200 (within 20 s), asking every 50 ms.
HttpResponse when_ready(int port, const std::string& path) {
  HttpResponse r;
  for (int i = 0; i < 400; ++i) {
    r = http_request(port, "GET", path);
    if (r.status == 200) break;
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  return r;
}

cv::Mat decode(const std::string& bytes, int flags) {
  return cv::imdecode(
      cv::Mat(1, static_cast<int>(bytes.size()), CV_8U, const_cast<char*>(bytes.data())), flags);
}

// The firmware on the simulated board with the view on, run in a thread of its own.
struct PageServed {
  test::SimRig rig{160, 96, 8};
  int port = test::free_port();
  std::unique_ptr<Firmware> fw;
  Kept kept;
  std::atomic<bool> stop{false};
  std::thread loop;
  PageServed() {
    BoardConfig config = rig.parse("outputs: {view: {port: " + std::to_string(port) +
                                   ", picture_hz: 20, quality: 95}}\n");
    rig.add_cascade(config);
    fw = std::make_unique<Firmware>(rig.replaying(config, 3));
    fw->frame_loop().set_observer(&kept);
    loop = std::thread([this] { fw->run(0, stop); });
  }
  ~PageServed() {
    stop = true;
    loop.join();
  }
};

TEST(ViewPage, ThePageAndItsApiAnswerAsABrowserAsks) {
  PageServed served;
  const int port = served.port;
  const HttpResponse page = when_ready(port, "/");
  ASSERT_EQ(page.status, 200);
  EXPECT_EQ(page.type, "text/html; charset=utf-8");
  EXPECT_NE(page.body.find("<title>Epipole live view</title>"), std::string::npos);
  EXPECT_EQ(page.body.find("http"), std::string::npos) << "nothing fetched from elsewhere";

  const HttpResponse health = when_ready(port, "/api/health");
  ASSERT_EQ(health.status, 200);
  EXPECT_EQ(health.type, "application/json");
  const json h = json::parse(health.body);
  EXPECT_GT(h["frames"].get<int>(), 0);
  EXPECT_TRUE(h.contains("outputs_dropped"));

  const HttpResponse frame = when_ready(port, "/api/frame.json");  // the page asks: pictures come
  ASSERT_EQ(frame.status, 200);
  const json f = json::parse(frame.body);
  EXPECT_EQ(f["board"], "test-sim");
  EXPECT_EQ(f["width"], 160);
  EXPECT_GT(f["corners"].size(), 10u);
  EXPECT_TRUE(f["detections"].is_array());
  EXPECT_EQ(f["max_disparity"], 32);

  const HttpResponse left = when_ready(port, "/api/left.jpg");
  ASSERT_EQ(left.status, 200);
  EXPECT_EQ(left.type, "image/jpeg");
  const cv::Mat gray = decode(left.body, cv::IMREAD_UNCHANGED);
  ASSERT_EQ(gray.type(), CV_8UC1);
  ASSERT_EQ(gray.cols, 160);
  ASSERT_EQ(gray.rows, 96);
  // One of the images the pipeline rectified, within JPEG's loss at quality 95.
  double closest = 255;
  for (const GrayImage& image : served.rig.images(3).left) {
    const cv::Mat mine(96, 160, CV_8UC1, const_cast<std::uint8_t*>(image.view().row(0)),
                       static_cast<std::size_t>(image.stride()));
    closest = std::min(closest, cv::mean(cv::abs(gray - mine))[0]);
  }
  EXPECT_LT(closest, 3.0);

  const HttpResponse disparity = when_ready(port, "/api/disparity.jpg");
  ASSERT_EQ(disparity.status, 200);
  const cv::Mat colour = decode(disparity.body, cv::IMREAD_COLOR);
  ASSERT_EQ(colour.cols, 160);
  // The rig's constant disparity (8 of 32) in the middle, as the colour table has it.
  const view::Rgb want = view::disparity_colours()[8 * 16 * 255 / (32 * 16)];
  const cv::Vec3b got = colour.at<cv::Vec3b>(48, 80);  // BGR
  EXPECT_NEAR(got[2], want[0], 24);
  EXPECT_NEAR(got[1], want[1], 24);
  EXPECT_NEAR(got[0], want[2], 24);

  const HttpResponse colours = http_request(port, "GET", "/api/colours.json");
  ASSERT_EQ(colours.status, 200);
  EXPECT_EQ(json::parse(colours.body).size(), 256u);

  EXPECT_EQ(http_request(port, "GET", "/nothing/here").status, 404);
  EXPECT_EQ(http_request(port, "GET", "/api/nothing").status, 404);
  EXPECT_EQ(http_request(port, "POST", "/api/health").status, 405);
  EXPECT_EQ(http_request(port, "DELETE", "/").status, 405);
  const HttpResponse head = http_request(port, "HEAD", "/");
  EXPECT_EQ(head.status, 405);
  EXPECT_EQ(head.body, "") << "a HEAD answer has no body";
  EXPECT_EQ(http_request(port, "GET", "/api/left.jpg?frame=4000000000").status, 409)
      << "a pair that is not the latest";
}

// Headless Chromium (Debian's `chromium`, scripts/setup.sh) on `url`, with its own profile in
// `dir`: `what` is --screenshot=FILE or --dump-dom; what it printed.
std::string chromium(const std::filesystem::path& dir, const std::string& what,
                     const std::string& url) {
  const std::string command =
      "chromium --headless --no-sandbox --disable-gpu --disable-dev-shm-usage --no-first-run "
      "--hide-scrollbars --window-size=1400,900 --virtual-time-budget=4000 --user-data-dir=" +
      (dir / "profile").string() + " " + what + " " + url + " 2>/dev/null";
  FILE* pipe = popen(command.c_str(), "r");
  if (pipe == nullptr) return "";
  return test::finish_tool(pipe).out;
}

// The number in `data-uptime="N"` of a dumped page (the health table's), or -1.
long long shown_uptime(const std::string& dom) {
  const std::size_t at = dom.find("data-uptime=\"");
  return at == std::string::npos ? -1 : std::atoll(dom.c_str() + at + 13);
}

TEST(ViewPage, ChromiumShowsThePicturesInColourAndHealthThatChanges) {
  PageServed served;
  ASSERT_EQ(when_ready(served.port, "/api/health").status, 200);
  const test::TempDir dir;
  const std::string url = "http://127.0.0.1:" + std::to_string(served.port) + "/";
  chromium(dir.path(), "--screenshot=" + (dir.path() / "page.png").string(), url);
  const cv::Mat shot = cv::imread((dir.path() / "page.png").string(), cv::IMREAD_COLOR);
  ASSERT_FALSE(shot.empty()) << "no screenshot from chromium";
  // The disparity in colour: pixels far from gray (the page itself is gray on black).
  int coloured = 0, lit = 0;
  for (int y = 0; y < shot.rows; ++y) {
    for (int x = 0; x < shot.cols; ++x) {
      const cv::Vec3b p = shot.at<cv::Vec3b>(y, x);
      const int hi = std::max({p[0], p[1], p[2]}), lo = std::min({p[0], p[1], p[2]});
      if (hi - lo > 80) ++coloured;
      if (hi > 60 && hi - lo < 16) ++lit;  // the gray left image
    }
  }
  // Kept beside the test program (docs/live-view.png is one of these).
  cv::imwrite((std::filesystem::current_path() / "live-view.png").string(), shot);
  EXPECT_GT(coloured, 160 * 96 / 2) << "the disparity picture, in colour";
  EXPECT_GT(lit, 160 * 96 / 2) << "the left image, not blank";
  // Health as the page shows it, at two loads a moment apart: it moves on.
  const long long first = shown_uptime(chromium(dir.path(), "--dump-dom", url));
  std::this_thread::sleep_for(std::chrono::milliseconds(1500));
  const long long second = shown_uptime(chromium(dir.path(), "--dump-dom", url));
  EXPECT_GT(first, 0) << "the page shows health";
  EXPECT_GT(second, first) << "and the health it shows changes";
}

}  // namespace
}  // namespace epipole::firmware
