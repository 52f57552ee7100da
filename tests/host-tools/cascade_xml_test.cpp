// OpenCV's cascade XML (epipole_cascade_xml): every traincascade file of the data set reads, and
// compiles to a binary that reads back to the same cascade; malformed and inconsistent files
// are one-line errors naming the file and line.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include "epipole/core/error.hpp"
#include "epipole/tools/cascade_xml.hpp"
#include "test_data.hpp"

namespace epipole::tools {
namespace {

using vision::CascadeFeatureType;
using vision::CascadeModel;

std::string read_text(const std::filesystem::path& file) {
  std::ifstream in(file, std::ios::binary);
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

// A small Haar cascade with what the big ones have: stumps, a tree of three nodes, a tilted
// feature and a three-rectangle feature.
constexpr const char* kTinyHaar = R"(<?xml version="1.0"?>
<opencv_storage>
<cascade type_id="opencv-cascade-classifier"><stageType>BOOST</stageType>
  <featureType>HAAR</featureType>
  <height>12</height>
  <width>10</width>
  <featureParams><maxCatCount>0</maxCatCount></featureParams>
  <stageNum>2</stageNum>
  <stages>
    <_>
      <maxWeakCount>2</maxWeakCount>
      <stageThreshold>-1.5e+00</stageThreshold>
      <weakClassifiers>
        <_><internalNodes>0 -1 0 -3.1e-02</internalNodes>
          <leafValues>-0.8 0.75</leafValues></_>
        <_><internalNodes>0 -1 1 1.2e-02</internalNodes>
          <leafValues>0.5 -0.6</leafValues></_></weakClassifiers></_>
    <_>
      <maxWeakCount>1</maxWeakCount>
      <stageThreshold>0.25</stageThreshold>
      <weakClassifiers>
        <_><!-- a tree: root, then its right child -->
          <internalNodes>2 1 2 -2.5e-02 0 -1 3 4.0e-03 -2 -3 0 1.0e-02</internalNodes>
          <leafValues>-0.5 0.25 0.75 -1.0</leafValues></_></weakClassifiers></_></stages>
  <features>
    <_><rects><_>1 1 8 4 -1.</_><_>1 3 8 2 2.</_></rects><tilted>0</tilted></_>
    <_><rects><_>0 0 9 12 -1.</_><_>3 0 3 12 3.</_></rects></_>
    <_><rects><_>5 1 3 2 -1.</_><_>5 2 2 1 2.</_></rects><tilted>1</tilted></_>
    <_><rects><_>2 2 6 6 -1.</_><_>2 2 3 3 2.</_><_>5 5 3 3 2.</_></rects></_></features>
</cascade>
</opencv_storage>
)";

constexpr const char* kTinyLbp = R"(<?xml version="1.0"?>
<opencv_storage>
<cascade>
  <stageType>BOOST</stageType>
  <featureType>LBP</featureType>
  <height>9</height>
  <width>12</width>
  <featureParams><maxCatCount>256</maxCatCount></featureParams>
  <stages>
    <_>
      <stageThreshold>-0.5</stageThreshold>
      <weakClassifiers>
        <_><internalNodes>0 -1 1 -1 -1 -17409 -1 -1 -1 -1 -1</internalNodes>
          <leafValues>-0.99 -0.39</leafValues></_>
        <_><internalNodes>0 -1 0 -21569 -20545 -1 -1 -20545 -1 0 2147483647</internalNodes>
          <leafValues>0.5 -0.25</leafValues></_></weakClassifiers></_></stages>
  <features>
    <_><rect>0 0 4 3</rect></_>
    <_><rect>3 0 2 2</rect></_></features>
</cascade>
</opencv_storage>
)";

std::string replaced(std::string text, const std::string& from, const std::string& to) {
  const auto at = text.find(from);
  EXPECT_NE(at, std::string::npos) << from;
  if (at != std::string::npos) text.replace(at, from.size(), to);
  return text;
}

void expect_error(const std::string& text, const std::string& message) {
  try {
    parse_cascade_xml(text, "bad.xml");
    ADD_FAILURE() << "no error; expected one with: " << message;
  } catch (const Error& e) {
    const std::string what = e.what();
    EXPECT_EQ(what.rfind("bad.xml: ", 0), 0u) << what;
    EXPECT_NE(what.find(message), std::string::npos) << what;
    EXPECT_EQ(what.find('\n'), std::string::npos) << what;
  }
}

TEST(CascadeXml, ReadsTheTinyCascades) {
  const CascadeModel haar = parse_cascade_xml(kTinyHaar, "tiny.xml");
  EXPECT_EQ(haar.feature_type(), CascadeFeatureType::haar);
  EXPECT_EQ(haar.window_width(), 10);
  EXPECT_EQ(haar.window_height(), 12);
  EXPECT_EQ(haar.stage_count(), 2u);
  EXPECT_EQ(haar.weak_count(), 3u);
  EXPECT_EQ(haar.feature_count(), 4u);
  EXPECT_FALSE(haar.stump_based());
  EXPECT_TRUE(haar.has_tilted_features());
  const vision::CascadeData& d = haar.data();
  EXPECT_EQ(d.stages[0].threshold, -1.5f - 1e-5f);
  EXPECT_EQ(d.node_counts, (std::vector<int>{1, 1, 3}));
  EXPECT_EQ(d.nodes[2].left, 2);
  EXPECT_EQ(d.nodes[2].right, 1);
  EXPECT_EQ(d.nodes[3].feature, 3);
  EXPECT_EQ(d.nodes[4].left, -2);
  EXPECT_EQ(d.nodes[4].threshold, static_cast<float>(1.0e-02));
  EXPECT_EQ(d.leaves.size(), 8u);
  EXPECT_EQ(d.haar_features[3].rect_count, 3);
  EXPECT_EQ(d.haar_features[3].rects[2].weight, 2.0f);

  const CascadeModel lbp = parse_cascade_xml(kTinyLbp, "tiny-lbp.xml");
  EXPECT_EQ(lbp.feature_type(), CascadeFeatureType::lbp);
  EXPECT_TRUE(lbp.stump_based());
  ASSERT_EQ(lbp.data().subsets.size(), 16u);
  EXPECT_EQ(lbp.data().subsets[2], static_cast<std::uint32_t>(-17409));
  EXPECT_EQ(lbp.data().subsets[15], 2147483647u);
  EXPECT_EQ(lbp.data().lbp_features[1].block_width, 2);
}

TEST(CascadeXml, EveryTraincascadeFileOfTheDataSetReadsAndCompiles) {
  int files = 0;
  for (const char* folder : {"cascades/haarcascades", "cascades/lbpcascades"}) {
    for (const auto& entry : std::filesystem::directory_iterator(test::data_file(folder))) {
      const std::string text = read_text(entry.path());
      if (text.find("opencv-haar-classifier") != std::string::npos) continue;  // old format
      const CascadeModel model = parse_cascade_xml(text, entry.path().string());
      const std::vector<std::uint8_t> binary = model.to_binary();
      const CascadeModel again = CascadeModel::from_binary(binary, "compiled");
      EXPECT_EQ(again.data(), model.data()) << entry.path();
      EXPECT_EQ(again.to_binary(), binary) << entry.path();
      EXPECT_LT(binary.size(), text.size() / 2) << entry.path() << ": the binary is compact";
      ++files;
    }
  }
  EXPECT_GE(files, 20);
}

TEST(CascadeXml, TheTwoFaceCascadesHaveTheirKnownShape) {
  const CascadeModel haar =
      load_cascade(test::data_file("cascades/haarcascades/haarcascade_frontalface_default.xml"));
  EXPECT_EQ(haar.window_width(), 24);
  EXPECT_EQ(haar.stage_count(), 25u);
  EXPECT_EQ(haar.weak_count(), 2913u);
  EXPECT_EQ(haar.feature_count(), 2913u);
  EXPECT_TRUE(haar.stump_based());
  EXPECT_FALSE(haar.has_tilted_features());
  const CascadeModel lbp =
      load_cascade(test::data_file("cascades/lbpcascades/lbpcascade_frontalface_improved.xml"));
  EXPECT_EQ(lbp.feature_type(), CascadeFeatureType::lbp);
  EXPECT_EQ(lbp.window_width(), 45);
  EXPECT_EQ(lbp.stage_count(), 19u);
  EXPECT_EQ(lbp.weak_count(), 149u);
  EXPECT_EQ(lbp.feature_count(), 142u);
  const CascadeModel trees =
      load_cascade(test::data_file("cascades/haarcascades/haarcascade_eye_tree_eyeglasses.xml"));
  EXPECT_FALSE(trees.stump_based());
  EXPECT_TRUE(trees.has_tilted_features());
  EXPECT_EQ(trees.weak_count(), 851u);
}

TEST(CascadeXml, LoadCascadeTellsBinaryFromXml) {
  const std::string file = ::testing::TempDir() + "epipole-tiny-cascade.bin";
  const std::vector<std::uint8_t> binary = parse_cascade_xml(kTinyHaar, "tiny.xml").to_binary();
  std::ofstream(file, std::ios::binary)
      .write(reinterpret_cast<const char*>(binary.data()),
             static_cast<std::streamsize>(binary.size()));
  EXPECT_EQ(load_cascade(file).data(), parse_cascade_xml(kTinyHaar, "tiny.xml").data());
  EXPECT_THROW(load_cascade(::testing::TempDir() + "no-such-cascade.xml"), Error);
}

TEST(CascadeXml, BadFilesAreOneLineErrors) {
  const std::string haar = kTinyHaar;
  expect_error(haar.substr(0, haar.size() / 2), "malformed XML");
  expect_error("", "malformed XML");
  expect_error("<opencv_storage/>", "is empty");
  expect_error("<other/>", "not an OpenCV file");
  expect_error(replaced(haar, "<featureType>HAAR", "<featureType>HOG"), "HOG cascades");
  expect_error(replaced(haar, "<featureType>HAAR", "<featureType>SURF"),
               "unknown feature type 'SURF'");
  expect_error(replaced(haar, "<stageType>BOOST", "<stageType>CART"), "stage type 'CART'");
  expect_error(
      replaced(haar, "type_id=\"opencv-cascade-classifier\"", "type_id=\"opencv-haar-classifier\""),
      "old OpenCV Haar format");
  expect_error(replaced(haar, "<leafValues>0.5 -0.6</leafValues>", "<leafValues>0.5</leafValues>"),
               "leaf count mismatch");
  expect_error(replaced(haar, "0 -1 1 1.2e-02", "0 -1 1 1.2e-02 7"), "not a multiple of 4");
  expect_error(replaced(haar, "0 -1 1 1.2e-02", "0 -1 9 1.2e-02"), "feature 9 out of range");
  expect_error(replaced(haar, "0 -1 1 1.2e-02", "0 -5 1 1.2e-02"), "must have children 0 -1");
  expect_error(replaced(haar, "-2 -3 0 1.0e-02", "-2 -9 0 1.0e-02"), "points nowhere");
  expect_error(replaced(haar, "2 1 2 -2.5e-02 0 -1 3", "2 1 2 -2.5e-02 0 1 3"), "points nowhere");
  expect_error(replaced(haar, "0 -1 0 -3.1e-02", "0 -1 0 abc"), "'abc' is not a number");
  expect_error(replaced(haar, "0 -1 0 -3.1e-02", "0.5 -1 0 -3.1e-02"), "not an integer");
  expect_error(replaced(haar, "<_>3 0 3 12 3.</_>", "<_>3 0 8 12 3.</_>"), "outside the 10x12");
  expect_error(replaced(haar, "<_>5 1 3 2 -1.</_>", "<_>1 1 3 2 -1.</_>"), "(tilted)");
  expect_error(replaced(haar, "<stageThreshold>0.25", "<stageThreshold>1e39"), "range of float");
  expect_error(replaced(haar, "<width>10</width>", ""), "has no <width>");
  expect_error(replaced(haar, "<maxCatCount>0<", "<maxCatCount>256<"), "maxCatCount 256");
  expect_error(replaced(kTinyLbp, "<rect>3 0 2 2</rect>", "<rect>3 0 4 2</rect>"),
               "outside the 12x9");
  expect_error(replaced(kTinyLbp, "-1 -1 -1 -1 -1</internalNodes>", "-1 -1 -1 -1</internalNodes>"),
               "not a multiple of 11");
}

TEST(CascadeXml, ErrorsGiveTheLine) {
  try {
    parse_cascade_xml(
        replaced(kTinyHaar, "<leafValues>0.5 -0.6</leafValues>", "<leafValues>0.5</leafValues>"),
        "bad.xml");
    FAIL() << "no error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("bad.xml: line 17:"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace epipole::tools
