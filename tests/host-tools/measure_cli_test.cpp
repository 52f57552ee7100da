// epipole measure: distances and areas on a plane from one image. The image is a photograph of
// a poster (the data set's graf1.png, whose pixels are the poster's millimetres) seen through a
// known perspective, so every length and area on the poster is known exactly.
#include <gtest/gtest.h>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <filesystem>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>

#include "epipole/core/temporary_folder.hpp"
#include "run_tool.hpp"
#include "test_data.hpp"

namespace epipole::tools {
namespace {

// The poster (graf1: 1 px = 1 mm) photographed: where its point (x, y) mm lands in the photo.
struct Photo {
  TemporaryFolder dir{"epipole-measure"};
  cv::Matx33d poster_to_photo{0.62, -0.18, 140, 0.07, 0.55, 60, 2.2e-4, -1.5e-4, 1};
  std::filesystem::path file = dir.path() / "photo.png";
  Photo() {
    const cv::Mat poster = cv::imread(test::data_file("samples/graf1.png"), cv::IMREAD_GRAYSCALE);
    EXPECT_FALSE(poster.empty());
    cv::Mat photo;
    cv::warpPerspective(poster, photo, cv::Mat(poster_to_photo), cv::Size(640, 480),
                        cv::INTER_AREA);
    cv::imwrite(file.string(), photo);
  }
  // "u,v,u,v" of poster points (mm), and the same in metres.
  std::string pixels(std::initializer_list<cv::Point2d> mm) const {
    std::ostringstream out;
    out.precision(10);
    for (const cv::Point2d& p : mm) {
      const cv::Vec3d q = poster_to_photo * cv::Vec3d(p.x, p.y, 1);
      out << (out.tellp() > 0 ? "," : "") << q[0] / q[2] << "," << q[1] / q[2];
    }
    return out.str();
  }
  static std::string metres(std::initializer_list<cv::Point2d> mm) {
    std::ostringstream out;
    for (const cv::Point2d& p : mm)
      out << (out.tellp() > 0 ? "," : "") << p.x / 1000 << "," << p.y / 1000;
    return out.str();
  }
};

TEST(MeasureCli, DistancesAndAreasOnThePlaneOfAPhoto) {
  const Photo photo;
  const auto corners = {cv::Point2d(80, 60), cv::Point2d(720, 90), cv::Point2d(700, 580),
                        cv::Point2d(100, 560), cv::Point2d(400, 320)};
  const test::ToolResult r = test::run_tool(
      "measure " + photo.file.string() + " --points " + photo.pixels(corners) + " --world " +
          Photo::metres(corners) + " --measure " +
          photo.pixels({{200, 300}, {600, 300}, {600, 500}, {200, 500}}) + " --unwarp " +
          (photo.dir.path() / "poster.png").string() + " --scale 1000 --json",
      false);
  ASSERT_EQ(r.exit_code, 0) << r.out;
  const nlohmann::json j = nlohmann::json::parse(r.out);
  ASSERT_EQ(j["distances"].size(), 3u);
  EXPECT_NEAR(j["distances"][0].get<double>(), 0.4, 1e-4) << j.dump();
  EXPECT_NEAR(j["distances"][1].get<double>(), 0.2, 1e-4);
  EXPECT_NEAR(j["distances"][2].get<double>(), 0.4, 1e-4);
  EXPECT_NEAR(j["area"].get<double>(), 0.08, 1e-5);
  EXPECT_LT(j["rms_px"].get<double>(), 1e-6);
  for (const bool in : j["inliers"]) EXPECT_TRUE(in);
  // The unwarped poster (1 px = 1 mm, from 10 % before the points' extent) is graf1 again where
  // the photo was sharp enough.
  const cv::Mat poster = cv::imread(test::data_file("samples/graf1.png"), cv::IMREAD_GRAYSCALE);
  const cv::Mat view = cv::imread((photo.dir.path() / "poster.png").string(), cv::IMREAD_GRAYSCALE);
  ASSERT_FALSE(view.empty());
  const double x0 = 80 - 0.1 * 640, y0 = 60 - 0.1 * 520;
  double diff = 0;
  int n = 0;
  for (int y = 200; y < 480; y += 4) {
    for (int x = 200; x < 600; x += 4) {
      diff += std::abs(view.at<std::uint8_t>(static_cast<int>(y - y0), static_cast<int>(x - x0)) -
                       poster.at<std::uint8_t>(y, x));
      ++n;
    }
  }
  EXPECT_LT(diff / n, 25) << "the photo shrank the poster: fine detail is lost, not the picture";
}

TEST(MeasureCli, AWrongPointIsLeftOutAndSaid) {
  const Photo photo;
  const auto poster = {cv::Point2d(80, 60),   cv::Point2d(720, 90),  cv::Point2d(700, 580),
                       cv::Point2d(100, 560), cv::Point2d(400, 320), cv::Point2d(300, 150)};
  // The last point's plane coordinates mistyped.
  const std::string world = Photo::metres(poster);
  const std::string wrong = world.substr(0, world.rfind(',')) + ",0.45";
  const test::ToolResult r = test::run_tool("measure " + photo.file.string() + " --points " +
                                            photo.pixels(poster) + " --world " + wrong);
  ASSERT_EQ(r.exit_code, 0) << r.out;
  EXPECT_NE(r.out.find("plane from 5 of 6 points"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("point 6 left out"), std::string::npos) << r.out;
}

TEST(MeasureCli, BadPointsAreClearErrors) {
  const Photo photo;
  const std::string image = photo.file.string();
  const struct {
    std::string arguments, says;
  } cases[] = {
      {"--points 1,2,3,4,5,6 --world 0,0,1,0,1,1", "four points at least"},
      {"--points 1,2,3,4,5,6,7 --world 0,0,1,0,1,1,0", "7 numbers"},
      {"--points 10,10,20,10,20,20,10,20 --world 0,0,1,0,1,1", "--world 3"},
      {"--points 10,10,20,x,20,20,10,20 --world 0,0,1,0,1,1,0,1", "'x' is not a number"},
      {"--points 10,10,20,10,30,10,40,10 --world 0,0,1,0,1,1,0,1", "on a line"},
      {"--points 10,10,20,10,20,20,10,9999 --world 0,0,1,0,1,1,0,1", "outside the 640x480 image"},
      // A floor seen in perspective (its far edge shorter): its horizon lies above the points.
      {"--points 200,300,440,300,600,470,40,470 --world 0,0,1,0,1,1,0,1 --measure 320,20",
       "beyond the plane's horizon"},
      {"--points 200,300,440,300,600,470,40,470 --world 0,0,1,0,1,1,0,1 --unwarp " +
           (photo.dir.path() / "x.png").string() + " --scale 1e300",
       "give another --scale"},
  };
  for (const auto& c : cases) {
    const test::ToolResult r = test::run_tool("measure " + image + " " + c.arguments);
    EXPECT_NE(r.exit_code, 0) << c.arguments;
    EXPECT_NE(r.out.find(c.says), std::string::npos) << c.arguments << ": " << r.out;
    EXPECT_EQ(test::line_count(r.out), 1) << r.out;
  }
}

}  // namespace
}  // namespace epipole::tools
