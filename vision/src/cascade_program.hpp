#pragma once

// The cascade as the window kernels run it (internal to vision): every feature reduced to
// offsets into the integral images, which live in one buffer of 32-bit planes with a fixed row
// stride (upright sums at 0, squares at square_offset, tilted sums at tilted_offset), so the
// same offsets serve every pyramid level. Levels searched at every other column (OpenCV's step 2)
// keep each plane's even and odd columns apart, so that the windows at x = 0, 2, 4, ... read
// every corner from consecutive entries too.

#include <cstddef>
#include <cstdint>
#include <vector>

#include "epipole/vision/cascade.hpp"
#include "epipole/vision/cascade_model.hpp"

namespace epipole::vision::kernels {

// A Haar feature: up to three weighted rectangle sums, each four corners (p0 - p1 - p2 + p3).
// Unused rectangles have weight 0 and offsets 0 (a sum of 0), as OpenCV's.
struct HaarTerms {
  std::int32_t offsets[3][4] = {};
  float weights[3] = {};
  int rect_count = 0;  // 2 or 3: the third term is added only when present
};

// An LBP feature: the 4 x 4 grid of corners of its 3 x 3 blocks, row by row.
struct LbpTerms {
  std::int32_t offsets[16] = {};
};

struct ProgramNode {
  int feature = 0;
  float threshold = 0.0f;
  int left = 0;
  int right = 0;
};

struct ProgramStage {
  int first_weak = 0;
  int weak_count = 0;
  float threshold = 0.0f;
  // Fixed point (see CascadeProgram): the stage passes when the sum of the selected deltas is
  // at least this.
  std::int64_t fixed_threshold = 0;
  // The SIMD kernels' stumps of a Haar stage by kind (HaarStumpKind), in this order: six_count
  // six-corner stumps, pair_count two-rectangle ones, then three-rectangle ones (the sum does
  // not depend on the order: it is exact).
  int six_count = 0;
  int pair_count = 0;
  // The SIMD kernels add each delta in two 32-bit lanes, delta = high * 2^split_shift + low with
  // 0 <= low < 2^split_shift: the shift is the largest for which the low parts' sum cannot
  // overflow, and the program falls back to the reference kernel when the high parts' could (a
  // stage of thousands of stumps with leaves of very different sizes).
  int split_shift = 0;
};

// What a stump's evaluation reads besides its offsets (and an LBP stump's subset), in 16 bytes
// that a NEON core loads with one instruction (simd/neon.hpp, load_params).
struct alignas(16) StumpParams {
  enum : int {
    kWeight,     // Haar, integer weights: the second rectangle's weight (six corners: k)
    kThreshold,  // Haar: the node threshold, a float's bits
    kDeltaLow,   // the delta in fixed point as high * 2^ProgramStage::split_shift + low,
    kDeltaHigh,  // 0 <= low < 2^split_shift
  };
  std::int32_t words[4] = {};
};

// How the SIMD kernels form a Haar stump's value.
enum class HaarStumpKind {
  // Integer weights, two rectangles sharing two corners (a rectangle and its half, as OpenCV's
  // edge features are): (p0 + p1) - (p2 + p3) + weight * (p4 - p5) over the six distinct
  // corners, in offsets[0][0..3] and offsets[1][0..1].
  six_corners,
  two_rects,    // each rectangle p0 - p1 - p2 + p3, weighted
  three_rects,  // the same with a third
};

// Stumps for the SIMD kernels, a stage's in the order they are evaluated. Taking the left leaf
// adds the delta to the stage's fixed-point sum (the right leaves are folded into the stage's
// threshold). Offsets are in bytes, not entries (see cascade_simd.hpp).
struct HaarStump {
  std::int32_t offsets[3][4] = {};
  StumpParams params;
  // CascadeProgram::integer_weights: the first rectangle's corners are ordered so that its
  // weight is 1; the second's is in params, the third's here.
  std::int32_t third_weight = 0;
  float weights[3] = {};  // the float path's
};

struct LbpStump {
  std::int32_t offsets[16] = {};  // LbpTerms' in bytes
  std::uint8_t subset[32] = {};   // bit c & 7 of byte c >> 3: the left leaf for code c
  StumpParams params;             // the delta only
};

// Where integral entry (x, y) of a window lies relative to the window's (0, 0) entry. With
// odd_offset == 0 columns are in order; otherwise a row holds the even columns, the odd ones are
// odd_offset further, and neighbouring windows (two columns apart) are neighbouring entries.
struct IntegralLayout {
  std::ptrdiff_t row_stride = 0;
  std::ptrdiff_t odd_offset = 0;
  bool split() const { return odd_offset != 0; }
  std::int32_t at(int x, int y) const {
    return static_cast<std::int32_t>(split() ? (x & 1) * odd_offset + y * row_stride + (x >> 1)
                                             : y * row_stride + x);
  }
};

struct CascadeProgram {
  CascadeProgram(const CascadeModel& model, IntegralLayout layout, std::ptrdiff_t square_offset,
                 std::ptrdiff_t tilted_offset);
  // The tables' bytes.
  std::size_t bytes() const;

  CascadeFeatureType type;
  int window_width;
  int window_height;
  IntegralLayout layout;
  int position_step;  // columns between neighbouring windows: 2 for a split layout, else 1
  std::ptrdiff_t square_offset;
  // Haar: the variance window (1, 1, W - 2, H - 2) as OpenCV normalises it.
  std::int32_t norm_offsets[4] = {};
  double norm_area = 0.0;

  std::vector<HaarTerms> haar;
  std::vector<LbpTerms> lbp;
  std::vector<ProgramStage> stages;
  std::vector<int> weak_first_node;
  std::vector<int> weak_first_leaf;
  std::vector<ProgramNode> nodes;
  std::vector<float> leaves;
  std::vector<std::uint32_t> subsets;  // LBP: 8 words per node
  bool stump_based;

  // Stage sums in fixed point: every leaf is an integer multiple of 2^-fixed_shift, and when
  // fixed_point_exact no stage's sum of leaf magnitudes reaches 2^52 units, so OpenCV's double
  // sums are exact and equal the SIMD kernels' integer sums (ProgramStage::split_shift). (It
  // also requires the window to be small enough for exact variance sums: below about 600 x 600
  // pixels.)
  int fixed_shift = 0;
  bool fixed_point_exact = false;
  // Haar: every rectangle weight is an integer, the first 1 or -1, and no weighted sum of a
  // window's pixels reaches 2^24, so the SIMD kernels form the feature values in integers: the
  // reference's float products and sums of such integers are exact, and equal.
  bool integer_weights = false;
  std::vector<HaarStump> haar_stumps;
  std::vector<LbpStump> lbp_stumps;

 private:
  void build_fixed_point();
  // One stage's fixed-point threshold and split shift, and each weak classifier's leaf delta;
  // false when they are not exact.
  bool fixed_stage(ProgramStage& stage, std::vector<std::int64_t>& deltas) const;
  void add_haar_stumps(ProgramStage& stage, const std::vector<std::int64_t>& deltas);
  void add_lbp_stumps(const ProgramStage& stage, const std::vector<std::int64_t>& deltas);
  HaarStump haar_stump(int node) const;  // a stump's (its weak classifier's only node)
};

// The windows of one row of one pyramid level: window i (of `positions`) at x = i *
// position_step has its (0, 0) integral entry at row[i] (the program's layout). Writes the x of
// each window that passes every stage and returns how many. A window rejected at the first
// stage (after passing the variance check) makes the next position be skipped, as in OpenCV.
int cascade_row_ref(const CascadeProgram& program, const std::uint32_t* row, int positions,
                    std::int32_t* hits);
int cascade_row_neon(const CascadeProgram& program, const std::uint32_t* row, int positions,
                     std::int32_t* hits);
int cascade_row_avx2(const CascadeProgram& program, const std::uint32_t* row, int positions,
                     std::int32_t* hits);
using CascadeRowKernel = int(const CascadeProgram&, const std::uint32_t*, int, std::int32_t*);

// integral_row_ref's entries before the first pixel: column 0 of each row it writes (the row
// above's, as nothing is summed yet) and the prefix's two leading zeros.
inline void integral_first_entries(const std::uint32_t* sum_above,
                                   const std::uint32_t* square_above, std::uint32_t* sum,
                                   std::uint32_t* square, std::uint32_t* prefix) {
  sum[0] = sum_above[0];
  if (square != nullptr) square[0] = square_above[0];
  if (prefix != nullptr) prefix[0] = prefix[1] = 0;
}

// integral_row_ref from column `from` on, continuing the row's running sums (the SIMD kernels'
// last columns).
inline void integral_columns(const std::uint8_t* row, int from, int width,
                             const std::uint32_t* sum_above, const std::uint32_t* square_above,
                             std::uint32_t* sum, std::uint32_t* square, std::uint32_t* prefix,
                             std::uint32_t running, std::uint32_t running_squares) {
  for (int x = from; x < width; ++x) {
    const std::uint32_t v = row[x];
    running += v;
    running_squares += v * v;
    sum[x + 1] = sum_above[x + 1] + running;
    if (square != nullptr) square[x + 1] = square_above[x + 1] + running_squares;
    if (prefix != nullptr) prefix[x + 2] = running;
  }
}

// tilted_row_ref's entries from column `from` on, then the running row's last entry.
inline void tilted_columns(const std::uint32_t* prefix, int from, int width,
                           const std::uint32_t* left_above, const std::uint32_t* right_above,
                           std::uint32_t* left, std::uint32_t* right, std::uint32_t* tilted) {
  for (int x = from; x <= width; ++x) {
    left[x] = left_above[x + 1] + prefix[x + 1];
    right[x + 1] = right_above[x] + prefix[x];
    tilted[x] = left[x] - right[x + 1];
  }
  left[width + 1] = left_above[width + 1] + prefix[width + 1];
}

// even[k] = row[2k], odd[k] = row[2k + 1] for the `count` entries of an integral row.
using SplitRowKernel = void(const std::uint32_t* row, int count, std::uint32_t* even,
                            std::uint32_t* odd);
void split_row_ref(const std::uint32_t* row, int count, std::uint32_t* even, std::uint32_t* odd);
void split_row_neon(const std::uint32_t* row, int count, std::uint32_t* even, std::uint32_t* odd);

// One window: 1 when it passes every stage, -s when stage s rejects it, -1 when the variance
// check does (Haar; OpenCV's window with a standard deviation of at most 10 grey levels).
int evaluate_window_ref(const CascadeProgram& program, const std::uint32_t* window);

// The variance normalisation of a Haar window, OpenCV's: nf = area * sqsum - sum^2 in double;
// false when nf <= 0 or area / sqrt(nf) >= 0.1, else factor = float(1 / sqrt(nf)).
bool variance_factor(const CascadeProgram& program, const std::uint32_t* window, float& factor);

}  // namespace epipole::vision::kernels
