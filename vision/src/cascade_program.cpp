// The cascade's evaluation tables and the reference window kernel: OpenCV 4.6's
// CascadeClassifier arithmetic (HaarEvaluator, LBPEvaluator, predictOrdered(Stump),
// predictCategorical(Stump)), written out for one window at a time.
#include "cascade_program.hpp"

#include <algorithm>
#include <bit>
#include <cmath>
#include <limits>

#include "epipole/core/error.hpp"
#include "kernel_set.hpp"

namespace epipole::vision::kernels {

namespace {

HaarTerms haar_terms(const HaarFeature& f, const IntegralLayout& layout,
                     std::ptrdiff_t tilted_offset) {
  HaarTerms t;
  t.rect_count = f.rect_count == 3 ? 3 : 2;
  const auto at = [&layout](int x, int y) { return layout.at(x, y); };
  for (int r = 0; r < f.rect_count; ++r) {
    const HaarRect& rect = f.rects[r];
    t.weights[r] = rect.weight;
    std::int32_t* o = t.offsets[r];
    if (f.tilted) {
      const auto base = static_cast<std::int32_t>(tilted_offset);
      o[0] = base + at(rect.x, rect.y);
      o[1] = base + at(rect.x - rect.height, rect.y + rect.height);
      o[2] = base + at(rect.x + rect.width, rect.y + rect.width);
      o[3] = base + at(rect.x + rect.width - rect.height, rect.y + rect.width + rect.height);
    } else {
      o[0] = at(rect.x, rect.y);
      o[1] = at(rect.x + rect.width, rect.y);
      o[2] = at(rect.x, rect.y + rect.height);
      o[3] = at(rect.x + rect.width, rect.y + rect.height);
    }
  }
  return t;
}

LbpTerms lbp_terms(const LbpFeature& f, const IntegralLayout& layout) {
  LbpTerms t;
  for (int r = 0; r < 4; ++r) {
    for (int c = 0; c < 4; ++c) {
      t.offsets[4 * r + c] = layout.at(f.x + c * f.block_width, f.y + r * f.block_height);
    }
  }
  return t;
}

// The stumps of the SIMD kernels hold byte offsets (cascade_simd.hpp): 4 per entry.
constexpr std::int32_t kEntryBytes = sizeof(std::uint32_t);

bool fits_in_bytes(std::int32_t entries) {
  constexpr std::int32_t kLimit = std::numeric_limits<std::int32_t>::max() / kEntryBytes;
  return entries >= -kLimit && entries <= kLimit;
}

std::int32_t in_bytes(std::int32_t entries) {
  return entries * kEntryBytes;
}

// The smallest shift that makes v * 2^shift an integer (floats carry 24 significant bits).
int exact_shift(float v) {
  if (v == 0.0f) return 0;
  int exponent = 0;
  std::frexp(v, &exponent);
  return 24 - exponent;
}

inline std::int32_t corner_sum(const std::uint32_t* w, const std::int32_t* o) {
  return static_cast<std::int32_t>(w[o[0]] - w[o[1]] - w[o[2]] + w[o[3]]);
}

inline float haar_value(const HaarTerms& t, const std::uint32_t* w) {
  float v = t.weights[0] * static_cast<float>(corner_sum(w, t.offsets[0])) +
            t.weights[1] * static_cast<float>(corner_sum(w, t.offsets[1]));
  if (t.rect_count == 3) v += t.weights[2] * static_cast<float>(corner_sum(w, t.offsets[2]));
  return v;
}

inline std::int32_t block(const std::uint32_t* w, const std::int32_t* o, int a, int b, int c,
                          int d) {
  return static_cast<std::int32_t>(w[o[a]] - w[o[b]] - w[o[c]] + w[o[d]]);
}

// The 8-bit LBP code: each of the 8 outer blocks compared with the centre, clockwise from the
// top-left (bit 7) to the middle-left (bit 0).
inline int lbp_code(const LbpTerms& t, const std::uint32_t* w) {
  const std::int32_t* o = t.offsets;
  const std::int32_t centre = block(w, o, 5, 6, 9, 10);
  return (block(w, o, 0, 1, 4, 5) >= centre ? 128 : 0) |
         (block(w, o, 1, 2, 5, 6) >= centre ? 64 : 0) |
         (block(w, o, 2, 3, 6, 7) >= centre ? 32 : 0) |
         (block(w, o, 6, 7, 10, 11) >= centre ? 16 : 0) |
         (block(w, o, 10, 11, 14, 15) >= centre ? 8 : 0) |
         (block(w, o, 9, 10, 13, 14) >= centre ? 4 : 0) |
         (block(w, o, 8, 9, 12, 13) >= centre ? 2 : 0) |
         (block(w, o, 4, 5, 8, 9) >= centre ? 1 : 0);
}

// Whether a Haar feature's value can be formed in integers (CascadeProgram::integer_weights):
// each rectangle lies inside the window (CascadeModel checks that), so its sum is at most 255
// times the window's pixels.
bool integer_weights_exact(const HaarTerms& t, int window_pixels) {
  if (t.weights[0] != 1.0f && t.weights[0] != -1.0f) return false;
  double bound = 0.0;
  for (const float w : t.weights) {
    if (w != std::trunc(w)) return false;
    bound += std::abs(static_cast<double>(w)) * 255.0 * window_pixels;
  }
  return bound < 0x1p24;
}

// The largest shift for which the low parts of `count` deltas (each below 2^shift) cannot
// overflow an int32 sum.
int split_shift_for(int count) {
  int shift = 0;
  while (shift < 62 && static_cast<std::int64_t>(count) * ((std::int64_t{2} << shift) - 1) <=
                           std::numeric_limits<std::int32_t>::max()) {
    ++shift;
  }
  return shift;
}

// A two-rectangle stump with integer weights as a six-corner one (HaarStumpKind::six_corners),
// when its corners merge into two +1, two -1, one +k and one -k; false otherwise.
bool merge_six_corners(HaarStump& s) {
  const std::int32_t weight = s.params.words[StumpParams::kWeight];
  std::vector<std::pair<std::int32_t, std::int32_t>> corners;  // offset, coefficient
  for (int r = 0; r < 2; ++r) {
    const std::int32_t w = r == 0 ? 1 : weight;
    const std::int32_t signs[4] = {w, -w, -w, w};
    for (int c = 0; c < 4; ++c) {
      const auto same = [&](const auto& corner) { return corner.first == s.offsets[r][c]; };
      const auto it = std::find_if(corners.begin(), corners.end(), same);
      if (it == corners.end()) {
        corners.emplace_back(s.offsets[r][c], signs[c]);
      } else {
        it->second += signs[c];
      }
    }
  }
  std::erase_if(corners, [](const auto& corner) { return corner.second == 0; });
  std::vector<std::int32_t> plus;
  std::vector<std::int32_t> minus;
  std::vector<std::pair<std::int32_t, std::int32_t>> weighted;
  for (const auto& [offset, coefficient] : corners) {
    if (coefficient == 1) {
      plus.push_back(offset);
    } else if (coefficient == -1) {
      minus.push_back(offset);
    } else {
      weighted.emplace_back(offset, coefficient);
    }
  }
  if (plus.size() != 2 || minus.size() != 2 || weighted.size() != 2 ||
      weighted[0].second != -weighted[1].second) {
    return false;
  }
  if (weighted[0].second < 0) std::swap(weighted[0], weighted[1]);
  s.offsets[0][0] = plus[0];
  s.offsets[0][1] = plus[1];
  s.offsets[0][2] = minus[0];
  s.offsets[0][3] = minus[1];
  s.offsets[1][0] = weighted[0].first;
  s.offsets[1][1] = weighted[1].first;
  s.offsets[1][2] = s.offsets[1][3] = 0;
  s.params.words[StumpParams::kWeight] = weighted[0].second;
  return true;
}

// Stores `delta` in `params` as high * 2^shift + low, 0 <= low < 2^shift.
void set_delta(StumpParams& params, std::int64_t delta, int shift) {
  const std::int64_t high = delta >> shift;  // floor: the low part is not negative
  params.words[StumpParams::kDeltaLow] =
      static_cast<std::int32_t>(delta - high * (std::int64_t{1} << shift));
  params.words[StumpParams::kDeltaHigh] = static_cast<std::int32_t>(high);
}

}  // namespace

CascadeProgram::CascadeProgram(const CascadeModel& model, IntegralLayout layout_,
                               std::ptrdiff_t square_offset_, std::ptrdiff_t tilted_offset)
    : type(model.feature_type()),
      window_width(model.window_width()),
      window_height(model.window_height()),
      layout(layout_),
      position_step(layout_.split() ? 2 : 1),
      square_offset(square_offset_),
      stump_based(model.stump_based()) {
  const CascadeData& d = model.data();
  const int w = window_width;
  const int h = window_height;
  const auto at = [this](int x, int y) { return layout.at(x, y); };
  norm_offsets[0] = at(1, 1);
  norm_offsets[1] = at(w - 1, 1);
  norm_offsets[2] = at(1, h - 1);
  norm_offsets[3] = at(w - 1, h - 1);
  norm_area = static_cast<double>(w - 2) * (h - 2);
  for (const HaarFeature& f : d.haar_features) haar.push_back(haar_terms(f, layout, tilted_offset));
  for (const LbpFeature& f : d.lbp_features) lbp.push_back(lbp_terms(f, layout));

  int weak = 0;
  int node = 0;
  int leaf = 0;
  for (const CascadeStage& s : d.stages) {
    stages.push_back({weak, s.weak_count, s.threshold, 0});
    for (int k = 0; k < s.weak_count; ++k, ++weak) {
      weak_first_node.push_back(node);
      weak_first_leaf.push_back(leaf);
      node += d.node_counts[weak];
      leaf += d.node_counts[weak] + 1;
    }
  }
  for (const CascadeNode& n : d.nodes) nodes.push_back({n.feature, n.threshold, n.left, n.right});
  leaves = d.leaves;
  subsets = d.subsets;
  if (stump_based) build_fixed_point();
}

HaarStump CascadeProgram::haar_stump(int node) const {
  const HaarTerms& t = haar[nodes[node].feature];
  HaarStump s;
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 4; ++c) s.offsets[r][c] = in_bytes(t.offsets[r][c]);
    s.weights[r] = t.weights[r];
  }
  if (integer_weights) {  // else the weights may not fit an integer
    if (t.weights[0] < 0.0f) {
      // p1 - p0 - p3 + p2 = -(p0 - p1 - p2 + p3): the first weight becomes 1.
      std::swap(s.offsets[0][0], s.offsets[0][1]);
      std::swap(s.offsets[0][2], s.offsets[0][3]);
    }
    s.params.words[StumpParams::kWeight] = static_cast<std::int32_t>(t.weights[1]);
    s.third_weight = static_cast<std::int32_t>(t.weights[2]);
  }
  s.params.words[StumpParams::kThreshold] = std::bit_cast<std::int32_t>(nodes[node].threshold);
  return s;
}

bool CascadeProgram::fixed_stage(ProgramStage& stage, std::vector<std::int64_t>& deltas) const {
  double magnitude = 0.0;
  std::int64_t base = 0;
  deltas.clear();
  for (int k = 0; k < stage.weak_count; ++k) {
    const int i = stage.first_weak + k;
    const double left = std::ldexp(static_cast<double>(leaves[2 * i]), fixed_shift);
    const double right = std::ldexp(static_cast<double>(leaves[2 * i + 1]), fixed_shift);
    magnitude += std::max(std::abs(left), std::abs(right));
    if (!(magnitude < 0x1p52)) return false;
    const auto left_fixed = static_cast<std::int64_t>(left);
    const auto right_fixed = static_cast<std::int64_t>(right);
    base += right_fixed;
    deltas.push_back(left_fixed - right_fixed);
  }
  // sum < T  <=>  base + selected < ceil(T * 2^shift) for integer sums.
  const double threshold = std::ceil(std::ldexp(static_cast<double>(stage.threshold), fixed_shift));
  if (!(std::abs(threshold) < 0x1p62)) return false;
  stage.fixed_threshold = static_cast<std::int64_t>(threshold) - base;
  stage.split_shift = split_shift_for(stage.weak_count);
  std::int64_t high_magnitude = 0;
  for (const std::int64_t d : deltas) high_magnitude += std::abs(d >> stage.split_shift);
  return high_magnitude <= std::numeric_limits<std::int32_t>::max();
}

// Grouped by kind, in HaarStumpKind's order: the kernels run a loop of each.
void CascadeProgram::add_haar_stumps(ProgramStage& stage, const std::vector<std::int64_t>& deltas) {
  std::vector<HaarStump> by_kind[3];  // indexed by HaarStumpKind
  for (int k = 0; k < stage.weak_count; ++k) {
    const int i = stage.first_weak + k;
    HaarStump stump = haar_stump(i);
    set_delta(stump.params, deltas[static_cast<std::size_t>(k)], stage.split_shift);
    const HaarStumpKind kind = haar[nodes[i].feature].rect_count == 3 ? HaarStumpKind::three_rects
                               : integer_weights && merge_six_corners(stump)
                                   ? HaarStumpKind::six_corners
                                   : HaarStumpKind::two_rects;
    by_kind[static_cast<int>(kind)].push_back(stump);
  }
  const auto count = [&by_kind](HaarStumpKind kind) {
    return static_cast<int>(by_kind[static_cast<int>(kind)].size());
  };
  stage.six_count = count(HaarStumpKind::six_corners);
  stage.pair_count = count(HaarStumpKind::two_rects);
  for (const auto& stumps : by_kind) {
    haar_stumps.insert(haar_stumps.end(), stumps.begin(), stumps.end());
  }
}

void CascadeProgram::add_lbp_stumps(const ProgramStage& stage,
                                    const std::vector<std::int64_t>& deltas) {
  for (int k = 0; k < stage.weak_count; ++k) {
    const int i = stage.first_weak + k;
    LbpStump stump;
    const LbpTerms& terms = lbp[nodes[i].feature];
    std::transform(std::begin(terms.offsets), std::end(terms.offsets), stump.offsets,
                   [](std::int32_t o) { return in_bytes(o); });
    set_delta(stump.params, deltas[static_cast<std::size_t>(k)], stage.split_shift);
    for (int word = 0; word < 8; ++word) {
      for (int byte = 0; byte < 4; ++byte) {
        stump.subset[4 * word + byte] =
            static_cast<std::uint8_t>(subsets[8 * i + word] >> (8 * byte));
      }
    }
    lbp_stumps.push_back(stump);
  }
}

// The stumps in fixed point for the SIMD kernels, when that is exact (fixed_point_exact). The
// cascade is stump-based: weak classifier i is node i.
void CascadeProgram::build_fixed_point() {
  // Integral images too large for 32-bit byte offsets are left to the reference kernel.
  const auto fit = [](const std::int32_t* offsets, int count) {
    return std::all_of(offsets, offsets + count, fits_in_bytes);
  };
  for (const HaarTerms& t : haar) {
    if (!fit(&t.offsets[0][0], 12)) return;
  }
  for (const LbpTerms& t : lbp) {
    if (!fit(t.offsets, 16)) return;
  }
  const int window_pixels = window_width * window_height;
  integer_weights = type == CascadeFeatureType::haar &&
                    std::all_of(haar.begin(), haar.end(), [&](const HaarTerms& t) {
                      return integer_weights_exact(t, window_pixels);
                    });
  for (const float v : leaves) fixed_shift = std::max(fixed_shift, exact_shift(v));
  fixed_point_exact = true;
  std::vector<std::int64_t> deltas;
  for (ProgramStage& stage : stages) {
    if (!fixed_stage(stage, deltas)) {
      fixed_point_exact = false;
      break;
    }
    if (type == CascadeFeatureType::haar) {
      add_haar_stumps(stage, deltas);
    } else {
      add_lbp_stumps(stage, deltas);
    }
  }
  // The SIMD kernels compute nf = area * squares - sum^2 exactly in int64 and convert it to
  // double; OpenCV's double arithmetic is exact too (so the two agree) while these fit 2^52.
  if (type == CascadeFeatureType::haar &&
      !(norm_area * 4294967295.0 < 0x1p52 && (255.0 * norm_area) * (255.0 * norm_area) < 0x1p52)) {
    fixed_point_exact = false;
  }
  if (!fixed_point_exact) {
    haar_stumps.clear();
    lbp_stumps.clear();
  }
}

std::size_t CascadeProgram::bytes() const {
  const auto size = [](const auto& v) { return v.size() * sizeof(v[0]); };
  return size(haar) + size(lbp) + size(stages) + size(weak_first_node) + size(weak_first_leaf) +
         size(nodes) + size(leaves) + size(subsets) + size(haar_stumps) + size(lbp_stumps);
}

bool variance_factor(const CascadeProgram& p, const std::uint32_t* window, float& factor) {
  const std::int32_t* o = p.norm_offsets;
  const auto sum =
      static_cast<std::int32_t>(window[o[0]] - window[o[1]] - window[o[2]] + window[o[3]]);
  const std::uint32_t* squares = window + p.square_offset;
  const std::uint32_t square_sum = squares[o[0]] - squares[o[1]] - squares[o[2]] + squares[o[3]];
  const double nf = p.norm_area * static_cast<double>(square_sum) -
                    static_cast<double>(sum) * static_cast<double>(sum);
  if (!(nf > 0.0)) return false;
  factor = static_cast<float>(1.0 / std::sqrt(nf));
  return p.norm_area * static_cast<double>(factor) < 0.1;
}

int evaluate_window_ref(const CascadeProgram& p, const std::uint32_t* window) {
  const bool lbp = p.type == CascadeFeatureType::lbp;
  float factor = 1.0f;
  if (!lbp && !variance_factor(p, window, factor)) return -1;
  const int stage_count = static_cast<int>(p.stages.size());
  for (int s = 0; s < stage_count; ++s) {
    const ProgramStage& stage = p.stages[s];
    double sum = 0.0;
    for (int k = 0; k < stage.weak_count; ++k) {
      const int weak = stage.first_weak + k;
      const int root = p.weak_first_node[weak];
      int index = 0;
      do {
        const ProgramNode& node = p.nodes[root + index];
        bool left = false;
        if (lbp) {
          const int code = lbp_code(p.lbp[node.feature], window);
          const std::uint32_t* subset = &p.subsets[8 * static_cast<std::size_t>(root + index)];
          left = (subset[code >> 5] & (1u << (code & 31))) != 0;
        } else {
          left = haar_value(p.haar[node.feature], window) * factor < node.threshold;
        }
        index = left ? node.left : node.right;
      } while (index > 0);
      sum += static_cast<double>(p.leaves[p.weak_first_leaf[weak] - index]);
    }
    if (sum < static_cast<double>(stage.threshold)) return -s;
  }
  return 1;
}

int cascade_row_ref(const CascadeProgram& program, const std::uint32_t* row, int positions,
                    std::int32_t* hits) {
  int count = 0;
  for (int i = 0; i < positions; ++i) {
    const int result = evaluate_window_ref(program, row + i);
    if (result > 0) hits[count++] = i * program.position_step;
    if (result == 0) ++i;  // rejected by the first stage: the next position is skipped
  }
  return count;
}

void split_row_ref(const std::uint32_t* row, int count, std::uint32_t* even, std::uint32_t* odd) {
  int k = 0;
  for (; 2 * k + 1 < count; ++k) {
    even[k] = row[2 * k];
    odd[k] = row[2 * k + 1];
  }
  if (2 * k < count) even[k] = row[2 * k];
}

}  // namespace epipole::vision::kernels
