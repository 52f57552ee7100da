#pragma once

// The cascade as the window kernels run it (internal to vision): every feature reduced to
// offsets into the integral images, which live in one buffer of 32-bit planes with a fixed row
// stride (upright sums at 0, squares at square_offset, tilted sums at tilted_offset), so the
// same offsets serve every pyramid level.

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
};

// Stumps in evaluation order, for the SIMD kernels. Taking the left leaf adds `delta` to the
// stage's fixed-point sum (the right leaves are folded into the stage's threshold).
struct HaarStump {
  HaarTerms terms;
  float threshold = 0.0f;
  std::int64_t delta = 0;
};

struct LbpStump {
  LbpTerms terms;
  std::uint8_t subset[32] = {};  // bit c & 7 of byte c >> 3: the left leaf for code c
  std::uint32_t words[8] = {};   // the same bits as OpenCV's words
  std::int64_t delta = 0;
};

struct CascadeProgram {
  CascadeProgram(const CascadeModel& model, std::ptrdiff_t stride, std::ptrdiff_t square_offset,
                 std::ptrdiff_t tilted_offset);

  CascadeFeatureType type;
  int window_width;
  int window_height;
  std::ptrdiff_t stride;
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
  // sums are exact and equal the int64 sums of the SIMD kernels.
  int fixed_shift = 0;
  bool fixed_point_exact = false;
  std::vector<HaarStump> haar_stumps;
  std::vector<LbpStump> lbp_stumps;
};

// Windows (x, row) for x = 0, step, 2 step, ... (`positions` of them) of one pyramid level,
// `row` pointing at column 0 of the window row in the upright plane. Writes the x of each
// window that passes every stage and returns how many. A window rejected at the first stage
// (after passing the variance check) makes the next position be skipped, as in OpenCV.
int cascade_row_ref(const CascadeProgram& program, const std::uint32_t* row, int positions,
                    int step, std::int32_t* hits);
int cascade_row_neon(const CascadeProgram& program, const std::uint32_t* row, int positions,
                     int step, std::int32_t* hits);
int cascade_row_avx2(const CascadeProgram& program, const std::uint32_t* row, int positions,
                     int step, std::int32_t* hits);
using CascadeRowKernel = int(const CascadeProgram&, const std::uint32_t*, int, int, std::int32_t*);

// One window: 1 when it passes every stage, -s when stage s rejects it, -1 when the variance
// check does (Haar; OpenCV's window with a standard deviation of at most 10 grey levels).
int evaluate_window_ref(const CascadeProgram& program, const std::uint32_t* window);

// The variance normalisation of a Haar window, OpenCV's: nf = area * sqsum - sum^2 in double;
// false when nf <= 0 or area / sqrt(nf) >= 0.1, else factor = float(1 / sqrt(nf)).
bool variance_factor(const CascadeProgram& program, const std::uint32_t* window, float& factor);

}  // namespace epipole::vision::kernels
