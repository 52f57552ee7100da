// epipole detect and epipole cascade-compile as a user runs them: boxes and their neighbour
// counts as JSON equal to cv::CascadeClassifier's, the same boxes from the XML and the compiled
// binary, the picture, and one-line errors for bad input.
#include <gtest/gtest.h>

#include <fstream>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/objdetect.hpp>
#include <string>
#include <vector>

#include "epipole/core/image_io.hpp"
#include "run_tool.hpp"
#include "test_data.hpp"

namespace {

using epipole::test::line_count;
using epipole::test::run_tool;
using Result = epipole::test::ToolResult;

std::string data(const char* name) {
  return epipole::test::data_file(name).string();
}

const std::string kHaar = "cascades/haarcascades/haarcascade_frontalface_default.xml";
const std::string kLbp = "cascades/lbpcascades/lbpcascade_frontalface_improved.xml";

// x, y, w, h, neighbors of each box.
std::vector<std::vector<int>> boxes_of(const nlohmann::json& json) {
  std::vector<std::vector<int>> boxes;
  for (const auto& d : json["detections"]) {
    boxes.push_back({d["x"].get<int>(), d["y"].get<int>(), d["w"].get<int>(), d["h"].get<int>(),
                     d["neighbors"].get<int>()});
  }
  return boxes;
}

std::vector<std::vector<int>> opencv_boxes(const std::string& cascade, const std::string& image,
                                           double scale, int neighbors, int min_size) {
  cv::setNumThreads(1);
  cv::CascadeClassifier classifier(cascade);
  std::vector<cv::Rect> rects;
  std::vector<int> counts;  // OpenCV 4.6's numDetections: the raw hits of each group
  classifier.detectMultiScale(cv::imread(image, cv::IMREAD_GRAYSCALE), rects, counts, scale,
                              neighbors, 0, cv::Size(min_size, min_size));
  std::vector<std::vector<int>> boxes;
  for (std::size_t i = 0; i < rects.size(); ++i) {
    const cv::Rect& r = rects[i];
    boxes.push_back({r.x, r.y, r.width, r.height, counts[i]});
  }
  return boxes;
}

TEST(DetectCli, BoxesEqualOpenCvFromXmlAndFromTheCompiledBinary) {
  const std::string image = data("samples/messi5.jpg");
  for (const std::string& cascade : {kHaar, kLbp}) {
    const std::string bin = ::testing::TempDir() + "epipole-cascade.bin";
    const Result compiled = run_tool("cascade-compile " + data(cascade.c_str()) + " " + bin);
    ASSERT_EQ(compiled.exit_code, 0) << compiled.out;
    EXPECT_EQ(line_count(compiled.out), 1) << compiled.out;
    EXPECT_NE(compiled.out.find("stages"), std::string::npos) << compiled.out;
    for (const auto& [scale, neighbors] : std::vector<std::pair<double, int>>{{1.1, 3}, {1.2, 1}}) {
      const std::string options = " --scale-factor " + std::to_string(scale) + " --min-neighbors " +
                                  std::to_string(neighbors) + " --min-size 30 --json";
      const Result from_xml =
          run_tool("detect " + image + " --cascade " + data(cascade.c_str()) + options, false);
      ASSERT_EQ(from_xml.exit_code, 0) << from_xml.out;
      const Result from_bin = run_tool("detect " + image + " --cascade " + bin + options, false);
      ASSERT_EQ(from_bin.exit_code, 0) << from_bin.out;
      const auto xml_json = nlohmann::json::parse(from_xml.out);
      const auto bin_json = nlohmann::json::parse(from_bin.out);
      EXPECT_EQ(xml_json["width"], 548);
      EXPECT_EQ(xml_json["height"], 342);
      EXPECT_EQ(boxes_of(xml_json), boxes_of(bin_json));
      EXPECT_EQ(boxes_of(xml_json),
                opencv_boxes(data(cascade.c_str()), image, scale, neighbors, 30))
          << cascade << " scale " << scale;
    }
  }
}

TEST(DetectCli, SummaryLinePictureAndKernelPaths) {
  const std::string image = data("samples/messi5.jpg");
  const std::string picture = ::testing::TempDir() + "epipole-detect.png";
  const Result r = run_tool("detect " + image + " --cascade " + data(kHaar.c_str()) +
                            " --min-size 30 --draw " + picture);
  ASSERT_EQ(r.exit_code, 0) << r.out;
  EXPECT_EQ(line_count(r.out), 1) << r.out;
  EXPECT_NE(r.out.find("detections"), std::string::npos) << r.out;
  const auto drawn = epipole::load_gray(picture);
  EXPECT_EQ(drawn.width(), 548);
  EXPECT_EQ(drawn.height(), 342);
  std::string first;
  for (const char* kernels : {"ref", "neon", "auto"}) {
    const Result k = run_tool(std::string("--kernels ") + kernels + " detect " + image +
                                  " --cascade " + data(kLbp.c_str()) + " --min-neighbors 0 --json",
                              false);
    ASSERT_EQ(k.exit_code, 0) << k.out;
    const std::string boxes = nlohmann::json::parse(k.out)["detections"].dump();
    if (first.empty()) first = boxes;
    EXPECT_EQ(boxes, first) << kernels;
  }
}

TEST(DetectCli, BadInputIsAOneLineError) {
  const std::string image = data("samples/messi5.jpg");
  const std::string dir = ::testing::TempDir();
  const std::string truncated = dir + "epipole-truncated.bin";
  const std::string flipped = dir + "epipole-flipped.bin";
  const std::string good = dir + "epipole-good.bin";
  ASSERT_EQ(run_tool("cascade-compile " + data(kLbp.c_str()) + " " + good).exit_code, 0);
  {
    std::ifstream in(good, std::ios::binary);
    std::vector<char> bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    std::ofstream(truncated, std::ios::binary)
        .write(bytes.data(), static_cast<long>(bytes.size() / 2));
    bytes[bytes.size() / 3] ^= 4;
    std::ofstream(flipped, std::ios::binary).write(bytes.data(), static_cast<long>(bytes.size()));
  }
  const std::string not_cascade = dir + "epipole-not-a-cascade.xml";
  std::ofstream(not_cascade)
      << "<?xml version=\"1.0\"?>\n<opencv_storage><x>1</x></opencv_storage>\n";
  const std::string broken = dir + "epipole-broken.xml";
  std::ofstream(broken) << "<?xml version=\"1.0\"?>\n<opencv_storage><cascade><stageType>BO";
  const struct {
    std::string arguments;
    std::string message;
  } cases[] = {
      {"detect " + image + " --cascade " + truncated, "truncated"},
      {"detect " + image + " --cascade " + flipped, "CRC-32 mismatch"},
      {"detect " + image + " --cascade " + not_cascade, "has no <stageType>"},
      {"detect " + image + " --cascade " + broken, "malformed XML"},
      {"detect " + image + " --cascade " + data("samples/messi5.jpg"), "malformed XML"},
      {"detect " + image + " --cascade " +
           data("cascades/haarcascades/haarcascade_licence_plate_rus_16stages.xml"),
       "old OpenCV Haar format"},
      {"cascade-compile " + broken + " " + dir + "out.bin", "malformed XML"},
      {"detect " + data("samples/left01.jpg") + ".missing --cascade " + good, ""},
  };
  for (const auto& c : cases) {
    const Result r = run_tool(c.arguments);
    EXPECT_NE(r.exit_code, 0) << c.arguments;
    EXPECT_LE(line_count(r.out), 2) << r.out;
    EXPECT_NE(r.out.find(c.message), std::string::npos) << c.arguments << "\n" << r.out;
  }
  const Result bad_scale =
      run_tool("detect " + image + " --cascade " + good + " --scale-factor 1.0");
  EXPECT_NE(bad_scale.exit_code, 0);
  EXPECT_EQ(run_tool("detect --help").exit_code, 0);
  EXPECT_EQ(run_tool("cascade-compile --help").exit_code, 0);
}

}  // namespace
