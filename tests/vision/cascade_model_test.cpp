// The cascade model and its compiled binary format: exact round trips, and every bad input
// (bad magic, newer versions, wrong lengths, truncation, CRC mismatches, every single-bit error,
// inconsistent models) an error naming the source.
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "cascade_test_models.hpp"
#include "epipole/core/error.hpp"
#include "epipole/vision/cascade_model.hpp"

namespace epipole::vision {
namespace {

CascadeModel random_model(CascadeFeatureType type, bool trees, std::uint32_t seed) {
  test::RandomCascadeShape shape;
  shape.type = type;
  shape.stages = 3;
  shape.max_nodes = trees ? 3 : 1;
  shape.tilted = type == CascadeFeatureType::haar;
  return CascadeModel(test::random_cascade(shape, seed), "random");
}

void expect_error(const std::vector<std::uint8_t>& bytes, const std::string& message) {
  try {
    CascadeModel::from_binary(bytes, "bad.bin");
    ADD_FAILURE() << "no error; expected one with: " << message;
  } catch (const Error& e) {
    const std::string what = e.what();
    EXPECT_EQ(what.rfind("bad.bin: ", 0), 0u) << what;
    EXPECT_NE(what.find(message), std::string::npos) << what;
  }
}

void expect_model_error(CascadeData data, const std::string& message) {
  try {
    CascadeModel(std::move(data), "model");
    ADD_FAILURE() << "no error; expected one with: " << message;
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find(message), std::string::npos) << e.what();
  }
}

TEST(CascadeBinary, RoundTripsExactly) {
  for (const CascadeFeatureType type : {CascadeFeatureType::haar, CascadeFeatureType::lbp}) {
    for (const bool trees : {false, true}) {
      const CascadeModel model = random_model(type, trees, 7);
      const std::vector<std::uint8_t> bytes = model.to_binary();
      const CascadeModel again = CascadeModel::from_binary(bytes, "again");
      EXPECT_EQ(again.data(), model.data());
      EXPECT_EQ(again.to_binary(), bytes);
      EXPECT_EQ(again.stump_based(), !trees);
      EXPECT_EQ(again.has_tilted_features(), model.has_tilted_features());
    }
  }
}

TEST(CascadeBinary, HeaderFieldsAreWhereTheDocsSay) {
  const CascadeModel model = random_model(CascadeFeatureType::lbp, false, 3);
  const std::vector<std::uint8_t> b = model.to_binary();
  const auto u32 = [&b](std::size_t at) {
    return b[at] | b[at + 1] << 8 | b[at + 2] << 16 | static_cast<std::uint32_t>(b[at + 3]) << 24;
  };
  EXPECT_EQ(std::string(b.begin(), b.begin() + 4), "EPCC");
  EXPECT_EQ(b[4] | b[5] << 8, CascadeModel::kFormatVersion);
  EXPECT_EQ(b[6], 1) << "LBP";
  EXPECT_EQ(b[8] | b[9] << 8, 24);
  EXPECT_EQ(u32(12), model.stage_count());
  EXPECT_EQ(u32(16), model.weak_count());
  EXPECT_EQ(u32(20), model.data().nodes.size());
  EXPECT_EQ(u32(24), model.data().leaves.size());
  EXPECT_EQ(u32(28), model.feature_count());
  EXPECT_EQ(u32(32), b.size() - 40);
}

TEST(CascadeBinary, BadHeadersAreErrors) {
  const std::vector<std::uint8_t> good =
      random_model(CascadeFeatureType::haar, true, 5).to_binary();
  auto bytes = good;
  bytes[0] = 'X';
  expect_error(bytes, "bad magic");
  bytes = good;
  bytes[4] = CascadeModel::kFormatVersion + 1;
  expect_error(bytes, "is newer than this reader's");
  bytes = good;
  bytes[4] = 0;
  expect_error(bytes, "version 0");
  bytes = good;
  bytes[6] = 7;
  expect_error(bytes, "unknown feature type 7");
  bytes = good;
  bytes[12] += 1;
  expect_error(bytes, "does not match the counts");
  bytes = good;
  bytes.push_back(0);
  expect_error(bytes, "trailing bytes");
  bytes = good;
  bytes[bytes.size() - 3] ^= 0x10;
  expect_error(bytes, "CRC-32 mismatch");
  expect_error({}, "too short");
}

TEST(CascadeBinary, EveryTruncationIsAnError) {
  const std::vector<std::uint8_t> good =
      random_model(CascadeFeatureType::lbp, false, 9).to_binary();
  for (std::size_t n = 0; n < good.size(); ++n) {
    const std::vector<std::uint8_t> prefix(good.begin(), good.begin() + static_cast<long>(n));
    EXPECT_THROW(CascadeModel::from_binary(prefix, "truncated"), Error) << n;
  }
}

TEST(CascadeBinary, EverySingleBitErrorIsCaught) {
  const std::vector<std::uint8_t> good =
      random_model(CascadeFeatureType::haar, true, 11).to_binary();
  for (std::size_t bit = 0; bit < good.size() * 8; ++bit) {
    auto bytes = good;
    bytes[bit / 8] ^= static_cast<std::uint8_t>(1u << (bit % 8));
    EXPECT_THROW(CascadeModel::from_binary(bytes, "flipped"), Error) << "bit " << bit;
  }
}

TEST(CascadeModelChecks, InconsistentModelsAreErrors) {
  const CascadeData good = random_model(CascadeFeatureType::haar, true, 13).data();
  CascadeData d = good;
  d.leaves.pop_back();
  expect_model_error(d, "leaf count mismatch");
  // The first node of the first real tree, and the first stump.
  std::size_t tree = 0;
  std::size_t stump = 0;
  for (std::size_t w = 0, first = 0; w < good.node_counts.size(); first += good.node_counts[w++]) {
    if (good.node_counts[w] > 1 && tree == 0) tree = first + 1;
    if (good.node_counts[w] == 1 && stump == 0) stump = first + 1;
  }
  ASSERT_GT(tree, 0u);
  ASSERT_GT(stump, 0u);
  d = good;
  d.nodes[tree - 1].left = 5;
  expect_model_error(d, "points nowhere");
  d = good;
  d.nodes[tree - 1].right = -1000;
  expect_model_error(d, "points nowhere");
  d = good;
  std::swap(d.nodes[stump - 1].left, d.nodes[stump - 1].right);
  expect_model_error(d, "must have children 0 -1");
  d = good;
  d.nodes[1].feature = static_cast<int>(d.haar_features.size());
  expect_model_error(d, "out of range");
  d = good;
  d.haar_features[0].rects[0].x = d.window_width;
  expect_model_error(d, "outside the 24x24 window");
  d = good;
  d.haar_features[0].rect_count = 4;
  expect_model_error(d, "rectangles (1 to 3 allowed)");
  d = good;
  d.stages[0].weak_count += 1;
  expect_model_error(d, "weak classifiers, the cascade has");
  d = good;
  d.stages.clear();
  expect_model_error(d, "no stages");
  d = good;
  d.window_width = 2;
  expect_model_error(d, "window size 2x24");
  d = good;
  d.leaves[3] = std::numeric_limits<float>::quiet_NaN();
  expect_model_error(d, "leaf 3 is not finite");
  d = good;
  d.subsets.push_back(1);
  expect_model_error(d, "subset words");

  CascadeData lbp = random_model(CascadeFeatureType::lbp, false, 15).data();
  lbp.lbp_features[0].block_width = 9;
  expect_model_error(lbp, "LBP feature 0");
}

}  // namespace
}  // namespace epipole::vision
