#pragma once

// A boosted cascade of Viola-Jones classifiers (OpenCV's "opencv-cascade-classifier": Haar or
// LBP features, stumps or small trees), in memory and in Epipole's compact binary format.
// Vision never reads files: the binary format is parsed from a byte span, and OpenCV's XML is
// read on the host (host-tools/cascade_xml). docs/vision.md, "Viola-Jones cascade", documents
// the format field by field.

#include <array>
#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <string_view>
#include <vector>

namespace epipole::vision {

enum class CascadeFeatureType : std::uint8_t { haar = 0, lbp = 1 };

std::string_view to_string(CascadeFeatureType type);

// One weighted rectangle of a Haar feature, in window coordinates. An upright rectangle covers
// [x, x + width) x [y, y + height); a tilted one (45 degrees) has its top corner at (x, y),
// its sides going down-right by `width` and down-left by `height` pixels.
struct HaarRect {
  int x = 0;
  int y = 0;
  int width = 0;
  int height = 0;
  float weight = 0.0f;
  friend bool operator==(const HaarRect&, const HaarRect&) = default;
};

struct HaarFeature {
  std::array<HaarRect, 3> rects{};
  int rect_count = 0;  // 1..3
  bool tilted = false;
  friend bool operator==(const HaarFeature&, const HaarFeature&) = default;
};

// A multi-block LBP feature: 3 x 3 blocks of block_width x block_height from (x, y).
struct LbpFeature {
  int x = 0;
  int y = 0;
  int block_width = 0;
  int block_height = 0;
  friend bool operator==(const LbpFeature&, const LbpFeature&) = default;
};

// A decision node. Haar: go left when the feature value < threshold. LBP: go left when bit
// `code` of the node's 256-bit subset is set. A child > 0 is a node of the same tree (by its
// index in the tree, always after this node); a child <= 0 is leaf -child of the tree.
struct CascadeNode {
  int left = 0;
  int right = 0;
  int feature = 0;
  float threshold = 0.0f;  // Haar only (0 for LBP)
  friend bool operator==(const CascadeNode&, const CascadeNode&) = default;
};

struct CascadeStage {
  int weak_count = 0;
  // Compared as OpenCV does: the stage passes when the sum of its leaves (in double) is not
  // below this value, which is OpenCV's stageThreshold - 1e-5 computed in float.
  float threshold = 0.0f;
  friend bool operator==(const CascadeStage&, const CascadeStage&) = default;
};

// Everything a cascade holds, as the readers fill it in. Stages own consecutive weak
// classifiers, weak classifiers own consecutive nodes (node_counts) and node_count + 1
// consecutive leaves.
struct CascadeData {
  static constexpr int kLbpSubsetWords = 8;  // 256 categories, 32 per word

  CascadeFeatureType feature_type = CascadeFeatureType::haar;
  int window_width = 0;
  int window_height = 0;
  std::vector<CascadeStage> stages;
  std::vector<int> node_counts;  // per weak classifier
  std::vector<CascadeNode> nodes;
  std::vector<float> leaves;
  std::vector<std::uint32_t> subsets;  // LBP: kLbpSubsetWords per node, bit c of word c / 32
  std::vector<HaarFeature> haar_features;
  std::vector<LbpFeature> lbp_features;
  friend bool operator==(const CascadeData&, const CascadeData&) = default;
};

// A checked cascade, fixed after construction.
class CascadeModel {
 public:
  static constexpr std::uint16_t kFormatVersion = 1;
  static constexpr int kMaxWindowSize = 1024;

  // Checks everything the detector relies on and throws Error("SOURCE: ...") naming the first
  // problem: counts that do not add up, a child pointing nowhere or backwards, a leaf count
  // mismatch, a feature index out of range, a feature rectangle outside the window, values
  // that are not finite.
  CascadeModel(CascadeData data, std::string_view source);

  // The compact binary format (docs/vision.md). Bad magic, a newer version, wrong lengths, a
  // CRC mismatch and everything the constructor checks are errors naming `source`.
  static CascadeModel from_binary(std::span<const std::uint8_t> bytes, std::string_view source);
  std::vector<std::uint8_t> to_binary() const;

  const CascadeData& data() const { return data_; }
  CascadeFeatureType feature_type() const { return data_.feature_type; }
  int window_width() const { return data_.window_width; }
  int window_height() const { return data_.window_height; }
  std::size_t stage_count() const { return data_.stages.size(); }
  std::size_t weak_count() const { return data_.node_counts.size(); }
  std::size_t feature_count() const;
  // Every weak classifier is a single node (the fast SIMD kernels handle these).
  bool stump_based() const { return stump_based_; }
  bool has_tilted_features() const { return has_tilted_; }

 private:
  CascadeData data_;
  bool stump_based_ = true;
  bool has_tilted_ = false;
};

}  // namespace epipole::vision
