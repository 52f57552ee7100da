#include "epipole/vision/cascade_model.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "epipole/core/bytes.hpp"
#include "epipole/core/crc32.hpp"
#include "epipole/core/error.hpp"

namespace epipole::vision {

std::string_view to_string(CascadeFeatureType type) {
  switch (type) {
    case CascadeFeatureType::haar:
      return "HAAR";
    case CascadeFeatureType::lbp:
      return "LBP";
  }
  return "unknown";
}

namespace {

bool finite(float v) {
  return std::isfinite(v);
}

void check_haar_feature(const HaarFeature& f, std::size_t index, int width, int height,
                        std::string_view source) {
  require(f.rect_count >= 1 && f.rect_count <= 3, source, ": feature ", index, " has ",
          f.rect_count, " rectangles (1 to 3 allowed)");
  for (int r = 0; r < 3; ++r) {
    const HaarRect& rect = f.rects[r];
    if (r >= f.rect_count) {
      require(rect == HaarRect{}, source, ": feature ", index, ": unused rectangle ", r,
              " is not zero");
      continue;
    }
    require(rect.width >= 1 && rect.height >= 1 && finite(rect.weight), source, ": feature ", index,
            ", rectangle ", r, ": size ", rect.width, "x", rect.height, " weight ", rect.weight,
            " (sizes must be positive, weights finite)");
    // The corners the sums read: upright (x, y)..(x + w, y + h); tilted (x, y), (x - h, y + h),
    // (x + w, y + w), (x + w - h, y + w + h).
    const bool inside = f.tilted ? rect.x - rect.height >= 0 && rect.y >= 0 &&
                                       rect.x + rect.width <= width &&
                                       rect.y + rect.width + rect.height <= height
                                 : rect.x >= 0 && rect.y >= 0 && rect.x + rect.width <= width &&
                                       rect.y + rect.height <= height;
    require(inside, source, ": feature ", index, ", rectangle ", r, (f.tilted ? " (tilted) " : " "),
            rect.x, " ", rect.y, " ", rect.width, " ", rect.height, " is outside the ", width, "x",
            height, " window");
  }
}

void check_lbp_feature(const LbpFeature& f, std::size_t index, int width, int height,
                       std::string_view source) {
  require(f.block_width >= 1 && f.block_height >= 1 && f.x >= 0 && f.y >= 0 &&
              f.x + 3 * f.block_width <= width && f.y + 3 * f.block_height <= height,
          source, ": LBP feature ", index, " (", f.x, " ", f.y, " ", f.block_width, " ",
          f.block_height, ") is outside the ", width, "x", height, " window");
}

// A tree's nodes: children point forward within the tree or at one of its leaves.
void check_tree(std::span<const CascadeNode> nodes, std::size_t weak, std::size_t feature_count,
                bool lbp, std::string_view source) {
  const int n = static_cast<int>(nodes.size());
  // OpenCV evaluates stump-based cascades as "left leaf when below the threshold"; a stump
  // with other children would mean something else there.
  require(n > 1 || (nodes[0].left == 0 && nodes[0].right == -1), source, ": weak classifier ", weak,
          ": a single-node tree must have children 0 -1, not ", nodes[0].left, " ", nodes[0].right);
  for (int i = 0; i < n; ++i) {
    const CascadeNode& node = nodes[i];
    for (const int child : {node.left, node.right}) {
      require(child > 0 ? child > i && child < n : child >= -n, source, ": weak classifier ", weak,
              ", node ", i, ": child ", child, " points nowhere (the tree has ", n, " nodes and ",
              n + 1, " leaves; children must point forward)");
    }
    require(node.feature >= 0 && static_cast<std::size_t>(node.feature) < feature_count, source,
            ": weak classifier ", weak, ", node ", i, ": feature ", node.feature, " out of range (",
            feature_count, " features)");
    require(lbp ? node.threshold == 0.0f : finite(node.threshold), source, ": weak classifier ",
            weak, ", node ", i, ": threshold ", node.threshold,
            lbp ? " (LBP nodes have none)" : " is not finite");
  }
}

}  // namespace

CascadeModel::CascadeModel(CascadeData data, std::string_view source) : data_(std::move(data)) {
  const CascadeData& d = data_;
  const bool lbp = d.feature_type == CascadeFeatureType::lbp;
  require(d.feature_type == CascadeFeatureType::haar || lbp, source, ": unknown feature type ",
          static_cast<int>(d.feature_type));
  require(d.window_width >= 3 && d.window_height >= 3 && d.window_width <= kMaxWindowSize &&
              d.window_height <= kMaxWindowSize,
          source, ": window size ", d.window_width, "x", d.window_height, " (3 to ", kMaxWindowSize,
          " allowed)");
  require(!d.stages.empty(), source, ": the cascade has no stages");
  std::size_t weaks = 0;
  for (std::size_t s = 0; s < d.stages.size(); ++s) {
    require(d.stages[s].weak_count >= 1, source, ": stage ", s, " has no weak classifiers");
    require(finite(d.stages[s].threshold), source, ": stage ", s, ": threshold ",
            d.stages[s].threshold, " is not finite");
    weaks += static_cast<std::size_t>(d.stages[s].weak_count);
  }
  require(weaks == d.node_counts.size(), source, ": the stages hold ", weaks,
          " weak classifiers, the cascade has ", d.node_counts.size());
  std::size_t nodes = 0;
  for (std::size_t w = 0; w < d.node_counts.size(); ++w) {
    require(d.node_counts[w] >= 1, source, ": weak classifier ", w, " has no nodes");
    nodes += static_cast<std::size_t>(d.node_counts[w]);
    stump_based_ = stump_based_ && d.node_counts[w] == 1;
  }
  require(nodes == d.nodes.size(), source, ": the weak classifiers hold ", nodes,
          " nodes, the cascade has ", d.nodes.size());
  require(d.leaves.size() == nodes + weaks, source, ": leaf count mismatch: ", d.leaves.size(),
          " leaves for ", nodes, " nodes in ", weaks, " trees (", nodes + weaks, " expected)");
  for (std::size_t i = 0; i < d.leaves.size(); ++i) {
    require(finite(d.leaves[i]), source, ": leaf ", i, " is not finite");
  }
  require(d.subsets.size() == (lbp ? nodes * CascadeData::kLbpSubsetWords : 0), source, ": ",
          d.subsets.size(), " subset words for ", nodes, " nodes (", (lbp ? 8 : 0),
          " per node expected)");
  require(lbp ? d.haar_features.empty() : d.lbp_features.empty(), source,
          ": features of the other type are present");
  const std::size_t features = lbp ? d.lbp_features.size() : d.haar_features.size();
  std::size_t first = 0;
  for (std::size_t w = 0; w < d.node_counts.size(); ++w) {
    const auto count = static_cast<std::size_t>(d.node_counts[w]);
    check_tree(std::span(d.nodes).subspan(first, count), w, features, lbp, source);
    first += count;
  }
  for (std::size_t i = 0; i < d.haar_features.size(); ++i) {
    check_haar_feature(d.haar_features[i], i, d.window_width, d.window_height, source);
    has_tilted_ = has_tilted_ || d.haar_features[i].tilted;
  }
  for (std::size_t i = 0; i < d.lbp_features.size(); ++i) {
    check_lbp_feature(d.lbp_features[i], i, d.window_width, d.window_height, source);
  }
}

std::size_t CascadeModel::feature_count() const {
  return data_.feature_type == CascadeFeatureType::lbp ? data_.lbp_features.size()
                                                       : data_.haar_features.size();
}

// The binary format, all little-endian:
//   header (40 bytes): magic "EPCC", u16 version, u8 feature type, u8 flags (bit 0: tilted
//   features), u16 window width, u16 window height, u32 stages, u32 weak classifiers, u32 nodes,
//   u32 leaves, u32 features, u32 payload length, u32 CRC-32 of the header's first 36 bytes
//   followed by the payload (so that every single-bit error anywhere is caught);
//   payload: stages {u32 weak count, f32 threshold}, weak classifiers {u32 node count}, nodes
//   {i32 left, i32 right, u32 feature, f32 threshold}, LBP subsets {8 x u32 per node}, leaves
//   {f32}, features: Haar {u8 rect count, u8 tilted, u16 0, 3 x {i16 x, y, w, h, f32 weight}},
//   LBP {i16 x, y, block width, block height}.
namespace {

constexpr std::uint8_t kMagic[4] = {'E', 'P', 'C', 'C'};
constexpr std::size_t kHeaderSize = 40;
constexpr std::size_t kStageSize = 8;
constexpr std::size_t kWeakSize = 4;
constexpr std::size_t kNodeSize = 16;
constexpr std::size_t kSubsetSize = 4 * CascadeData::kLbpSubsetWords;
constexpr std::size_t kLeafSize = 4;
constexpr std::size_t kHaarFeatureSize = 4 + 3 * 12;
constexpr std::size_t kLbpFeatureSize = 8;

struct Counts {
  std::uint64_t stages = 0, weaks = 0, nodes = 0, leaves = 0, features = 0;
  bool lbp = false;
  std::uint64_t payload_bytes() const {
    return stages * kStageSize + weaks * kWeakSize + nodes * kNodeSize +
           (lbp ? nodes * kSubsetSize : 0) + leaves * kLeafSize +
           features * (lbp ? kLbpFeatureSize : kHaarFeatureSize);
  }
};

constexpr std::size_t kCrcOffset = kHeaderSize - 4;

std::uint32_t checksum(std::span<const std::uint8_t> bytes) {
  return crc32(bytes.subspan(kHeaderSize), crc32(bytes.first(kCrcOffset)));
}

int checked_int(std::uint32_t v, const char* what, std::string_view source) {
  require(v <= static_cast<std::uint32_t>(std::numeric_limits<int>::max()), source, ": ", what, " ",
          v, " is out of range");
  return static_cast<int>(v);
}

}  // namespace

std::vector<std::uint8_t> CascadeModel::to_binary() const {
  const CascadeData& d = data_;
  const bool lbp = d.feature_type == CascadeFeatureType::lbp;
  const Counts counts{d.stages.size(), d.node_counts.size(), d.nodes.size(),
                      d.leaves.size(), feature_count(),      lbp};
  const auto payload_size = static_cast<std::size_t>(counts.payload_bytes());
  std::vector<std::uint8_t> bytes(kHeaderSize + payload_size);
  ByteWriter payload{std::span(bytes).subspan(kHeaderSize)};
  for (const CascadeStage& s : d.stages) {
    payload.u32(static_cast<std::uint32_t>(s.weak_count));
    payload.f32(s.threshold);
  }
  for (const int n : d.node_counts) payload.u32(static_cast<std::uint32_t>(n));
  for (const CascadeNode& n : d.nodes) {
    payload.i32(n.left);
    payload.i32(n.right);
    payload.u32(static_cast<std::uint32_t>(n.feature));
    payload.f32(n.threshold);
  }
  for (const std::uint32_t word : d.subsets) payload.u32(word);
  for (const float leaf : d.leaves) payload.f32(leaf);
  for (const HaarFeature& f : d.haar_features) {
    payload.u8(static_cast<std::uint8_t>(f.rect_count));
    payload.u8(f.tilted ? 1 : 0);
    payload.u16(0);
    for (const HaarRect& r : f.rects) {
      for (const int v : {r.x, r.y, r.width, r.height}) payload.i16(static_cast<std::int16_t>(v));
      payload.f32(r.weight);
    }
  }
  for (const LbpFeature& f : d.lbp_features) {
    for (const int v : {f.x, f.y, f.block_width, f.block_height}) {
      payload.i16(static_cast<std::int16_t>(v));
    }
  }
  ByteWriter header{std::span(bytes).first(kHeaderSize)};
  for (const std::uint8_t b : kMagic) header.u8(b);
  header.u16(kFormatVersion);
  header.u8(static_cast<std::uint8_t>(d.feature_type));
  header.u8(has_tilted_ ? 1 : 0);
  header.u16(static_cast<std::uint16_t>(d.window_width));
  header.u16(static_cast<std::uint16_t>(d.window_height));
  for (const std::uint64_t c : {counts.stages, counts.weaks, counts.nodes, counts.leaves,
                                counts.features, counts.payload_bytes()}) {
    header.u32(static_cast<std::uint32_t>(c));
  }
  header.u32(checksum(bytes));
  return bytes;
}

namespace {

// The header's fields, checked: the magic, a version this reader knows, the counts against the
// payload's length and the file's size, the CRC. Returns the counts and the flags; `d` gets the
// feature type and the window size.
Counts read_header(std::span<const std::uint8_t> bytes, std::string_view source, CascadeData& d,
                   std::uint8_t& flags) {
  require(bytes.size() >= kHeaderSize, source, ": ", bytes.size(),
          " bytes is too short for a compiled cascade (the header alone is ", kHeaderSize, ")");
  ByteReader header(bytes.first(kHeaderSize));
  std::uint8_t magic[4];
  for (std::uint8_t& b : magic) b = header.u8();
  require(std::equal(std::begin(magic), std::end(magic), std::begin(kMagic)), source,
          ": not a compiled cascade (bad magic; expected \"EPCC\")");
  const std::uint16_t version = header.u16();
  require(version <= CascadeModel::kFormatVersion, source, ": format version ", version,
          " is newer than this reader's (", CascadeModel::kFormatVersion, ")");
  require(version >= 1, source, ": format version 0 is invalid");
  const std::uint8_t type = header.u8();
  require(type <= 1, source, ": unknown feature type ", static_cast<int>(type));
  flags = header.u8();
  require((flags & ~1u) == 0, source, ": unknown flags 0x", std::hex, static_cast<int>(flags));
  d.feature_type = static_cast<CascadeFeatureType>(type);
  d.window_width = header.u16();
  d.window_height = header.u16();
  Counts counts;
  counts.lbp = d.feature_type == CascadeFeatureType::lbp;
  counts.stages = header.u32();
  counts.weaks = header.u32();
  counts.nodes = header.u32();
  counts.leaves = header.u32();
  counts.features = header.u32();
  const std::uint32_t payload_length = header.u32();
  const std::uint32_t crc = header.u32();
  require(payload_length == counts.payload_bytes(), source, ": payload length ", payload_length,
          " does not match the counts in the header (", counts.payload_bytes(), " bytes)");
  require(bytes.size() - kHeaderSize == payload_length, source, ": ", bytes.size() - kHeaderSize,
          " payload bytes, the header says ", payload_length,
          bytes.size() - kHeaderSize < payload_length ? " (truncated)" : " (trailing bytes)");
  // From here on every count is bounded by the file's size.
  const std::uint32_t actual_crc = checksum(bytes);
  require(actual_crc == crc, source, ": CRC-32 mismatch (computed 0x", std::hex, actual_crc,
          ", stored 0x", crc, ")");
  return counts;
}

void read_features(ByteReader& payload, const Counts& counts, CascadeData& d,
                   std::string_view source) {
  if (counts.lbp) {
    d.lbp_features.resize(static_cast<std::size_t>(counts.features));
    for (LbpFeature& f : d.lbp_features) {
      f.x = payload.i16();
      f.y = payload.i16();
      f.block_width = payload.i16();
      f.block_height = payload.i16();
    }
    return;
  }
  d.haar_features.resize(static_cast<std::size_t>(counts.features));
  for (HaarFeature& f : d.haar_features) {
    f.rect_count = payload.u8();
    const std::uint8_t tilted = payload.u8();
    require(tilted <= 1 && payload.u16() == 0, source, ": bad feature flags");
    f.tilted = tilted != 0;
    for (HaarRect& r : f.rects) {
      r.x = payload.i16();
      r.y = payload.i16();
      r.width = payload.i16();
      r.height = payload.i16();
      r.weight = payload.f32();
    }
  }
}

// The payload in the order the format lists it (above), into `d`.
void read_payload(std::span<const std::uint8_t> bytes, const Counts& counts, CascadeData& d,
                  std::string_view source) {
  ByteReader payload(bytes);
  d.stages.resize(static_cast<std::size_t>(counts.stages));
  for (CascadeStage& s : d.stages) {
    s.weak_count = checked_int(payload.u32(), "weak classifier count", source);
    s.threshold = payload.f32();
  }
  d.node_counts.resize(static_cast<std::size_t>(counts.weaks));
  for (int& n : d.node_counts) n = checked_int(payload.u32(), "node count", source);
  d.nodes.resize(static_cast<std::size_t>(counts.nodes));
  for (CascadeNode& n : d.nodes) {
    n.left = payload.i32();
    n.right = payload.i32();
    n.feature = checked_int(payload.u32(), "feature index", source);
    n.threshold = payload.f32();
  }
  d.subsets.resize(
      static_cast<std::size_t>(counts.lbp ? counts.nodes * CascadeData::kLbpSubsetWords : 0));
  for (std::uint32_t& word : d.subsets) word = payload.u32();
  d.leaves.resize(static_cast<std::size_t>(counts.leaves));
  for (float& leaf : d.leaves) leaf = payload.f32();
  read_features(payload, counts, d, source);
  require(payload.ok() && payload.remaining() == 0, source, ": payload layout mismatch");
}

}  // namespace

CascadeModel CascadeModel::from_binary(std::span<const std::uint8_t> bytes,
                                       std::string_view source) {
  CascadeData d;
  std::uint8_t flags = 0;
  const Counts counts = read_header(bytes, source, d, flags);
  read_payload(bytes.subspan(kHeaderSize), counts, d, source);
  CascadeModel model(std::move(d), source);
  require(model.has_tilted_ == ((flags & 1u) != 0), source,
          ": the tilted-features flag does not match the features");
  return model;
}

}  // namespace epipole::vision
