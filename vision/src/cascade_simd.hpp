#pragma once

// The cascade window kernel, written once over the word lanes of the vector vocabulary
// (simd/neon.hpp: 4 lanes, simd/avx2.hpp: 8 lanes). Lanes are neighbouring window positions of one
// row of one level (consecutive entries of its integral layout), so every corner of every feature
// is one vector load. Per group of lanes: the variance normalisation, then the stages; the group
// stops at the first stage that rejects all its lanes. OpenCV's rule "a window rejected by the
// first stage skips the next position" is applied after the first stage, 4 lanes at a time by
// table lookup, so the same windows are evaluated as in cascade_row_ref.
//
// Arithmetic is the reference's: the same float operations in the same order for Haar feature
// values (cascade_simd files are compiled with -ffp-contract=off) or the same values formed in
// integers where that is exact, the same integer LBP codes, and stage sums in fixed point, which
// equal the reference's double sums exactly (see CascadeProgram::fixed_point_exact; the detector
// uses this kernel only then). A stage's sum is kept in two 32-bit lanes per window (high and low
// parts, ProgramStage::split_shift) and joined in 64 bits for the stage's threshold.
#include <algorithm>
#include <array>
#include <cstdint>

#include "cascade_program.hpp"

namespace epipole::vision::kernels {

template <typename V>
typename V::I corner_sum(const std::uint32_t* w, const std::int32_t* o) {
  return V::addi(V::subi(V::subi(V::loadi(w + o[0]), V::loadi(w + o[1])), V::loadi(w + o[2])),
                 V::loadi(w + o[3]));
}

// A rectangle sum of a stump: its offsets are in bytes (CascadeProgram), since AArch64's vector
// loads scale a register offset only by the vector's size and entry offsets cost a shift a load.
template <typename V>
typename V::I stump_corner_sum(const std::uint8_t* w, const std::int32_t* o) {
  return V::addi(V::subi(V::subi(V::loadi_bytes(w + o[0]), V::loadi_bytes(w + o[1])),
                         V::loadi_bytes(w + o[2])),
                 V::loadi_bytes(w + o[3]));
}

// A stump's feature value before the variance factor. With integer weights
// (CascadeProgram::integer_weights) the weighted sum is formed in integers, every partial sum
// below 2^24, so it equals the reference's float products and sums of the same integers.
template <typename V, HaarStumpKind kKind, bool kIntegerWeights>
[[gnu::always_inline]] inline typename V::F haar_value(const HaarStump& s,
                                                       typename V::Params params,
                                                       const std::uint8_t* w) {
  const auto rect_sum = [&](int r) { return stump_corner_sum<V>(w, s.offsets[r]); };
  if constexpr (kKind == HaarStumpKind::six_corners) {
    const auto at = [&](int r, int c) { return V::loadi_bytes(w + s.offsets[r][c]); };
    const typename V::I ones = V::subi(V::addi(at(0, 0), at(0, 1)), V::addi(at(0, 2), at(0, 3)));
    return V::tof(V::mul_add_weight(ones, V::subi(at(1, 0), at(1, 1)), params));
  } else if constexpr (kIntegerWeights) {
    typename V::I value = V::mul_add_weight(rect_sum(0), rect_sum(1), params);
    if constexpr (kKind == HaarStumpKind::three_rects) {
      value = V::mul_addi(value, rect_sum(2), s.third_weight);
    }
    return V::tof(value);
  } else {
    typename V::F value = V::addf(V::mulf(V::splatf(s.weights[0]), V::tof(rect_sum(0))),
                                  V::mulf(V::splatf(s.weights[1]), V::tof(rect_sum(1))));
    if constexpr (kKind == HaarStumpKind::three_rects) {
      value = V::addf(value, V::mulf(V::splatf(s.weights[2]), V::tof(rect_sum(2))));
    }
    return value;
  }
}

template <typename V, HaarStumpKind kKind, bool kIntegerWeights>
[[gnu::always_inline]] inline void haar_stump(typename V::Acc& acc, const HaarStump& s,
                                              const std::uint8_t* w, typename V::F factor) {
  const typename V::Params params = V::load_params(s.params.words);
  const typename V::F value = haar_value<V, kKind, kIntegerWeights>(s, params, w);
  V::acc_add(acc, V::ltf(V::mulf(value, factor), V::threshold(params)), params);
}

// Stumps [first, last) of one kind, two at a time (half the loop's own instructions).
template <typename V, HaarStumpKind kKind, bool kIntegerWeights>
[[gnu::always_inline]] inline void haar_stumps(typename V::Acc& acc, const HaarStump* stumps,
                                               int first, int last, const std::uint8_t* w,
                                               typename V::F factor) {
  int k = first;
  for (; k + 2 <= last; k += 2) {
    haar_stump<V, kKind, kIntegerWeights>(acc, stumps[k], w, factor);
    haar_stump<V, kKind, kIntegerWeights>(acc, stumps[k + 1], w, factor);
  }
  if (k < last) haar_stump<V, kKind, kIntegerWeights>(acc, stumps[k], w, factor);
}

template <typename V, bool kIntegerWeights>
typename V::M haar_stage(const ProgramStage& stage, const HaarStump* stumps, const std::uint8_t* w,
                         typename V::F factor) {
  typename V::Acc acc = V::acc_zero();
  const int pairs_first = stage.six_count;
  const int triples_first = pairs_first + stage.pair_count;
  if constexpr (kIntegerWeights) {
    haar_stumps<V, HaarStumpKind::six_corners, true>(acc, stumps, 0, pairs_first, w, factor);
  }
  haar_stumps<V, HaarStumpKind::two_rects, kIntegerWeights>(acc, stumps, pairs_first, triples_first,
                                                            w, factor);
  for (int k = triples_first; k < stage.weak_count; ++k) {
    haar_stump<V, HaarStumpKind::three_rects, kIntegerWeights>(acc, stumps[k], w, factor);
  }
  return V::acc_at_least(acc, stage.split_shift, stage.fixed_threshold);
}

// LBP stumps. The 4 x 4 corners are read row by row: horizontal differences of each corner row,
// then each band of three blocks as the difference of two rows' differences (the same integer
// sums as OpenCV's p0 - p1 - p2 + p3), so few vectors are live at a time.
template <typename V>
typename V::M lbp_stage(const ProgramStage& stage, const LbpStump* stumps, const std::uint8_t* w) {
  using I = typename V::I;
  typename V::Acc acc = V::acc_zero();
  for (int k = 0; k < stage.weak_count; ++k) {
    const LbpStump& s = stumps[k];
    const std::int32_t* o = s.offsets;
    I above[3];
    I below[3];
    const auto differences = [&](int r, I* d) {
      const I c0 = V::loadi_bytes(w + o[4 * r]);
      const I c1 = V::loadi_bytes(w + o[4 * r + 1]);
      const I c2 = V::loadi_bytes(w + o[4 * r + 2]);
      const I c3 = V::loadi_bytes(w + o[4 * r + 3]);
      d[0] = V::subi(c0, c1);
      d[1] = V::subi(c1, c2);
      d[2] = V::subi(c2, c3);
    };
    differences(0, above);
    differences(1, below);
    const I top_left = V::subi(above[0], below[0]);
    const I top = V::subi(above[1], below[1]);
    const I top_right = V::subi(above[2], below[2]);
    differences(2, above);
    const I left = V::subi(below[0], above[0]);
    const I centre = V::subi(below[1], above[1]);
    const I right = V::subi(below[2], above[2]);
    differences(3, below);
    const I bottom_left = V::subi(above[0], below[0]);
    const I bottom = V::subi(above[1], below[1]);
    const I bottom_right = V::subi(above[2], below[2]);
    // Clockwise from the top-left block (bit 7) to the middle-left one (bit 0): pushed in at
    // the top from bit 0 on, so that the code ends in the top byte, where subset_bit reads it.
    const auto push = [&centre](I bits, I block) {
      return V::push_bit_high(bits, V::gei(block, centre));
    };
    I bits = push(V::zeroi(), left);
    bits = push(push(push(bits, bottom_left), bottom), bottom_right);
    bits = push(push(push(push(bits, right), top_right), top), top_left);
    V::acc_add(acc, V::subset_bit(s.subset, bits), V::load_params(s.params.words));
  }
  return V::acc_at_least(acc, stage.split_shift, stage.fixed_threshold);
}

// OpenCV's order over 4 neighbouring windows: one that is evaluated (its variance passes) and
// rejected by the first stage makes the next one be skipped. Indexed by ok | pass << 4 |
// skip << 8 (ok: the windows evaluated; pass: those the first stage passes; skip: the window
// before the four was rejected), it gives the windows that go on | skip-the-next << 4.
constexpr std::array<std::uint8_t, 512> first_stage_outcomes() {
  std::array<std::uint8_t, 512> table{};
  for (unsigned index = 0; index < table.size(); ++index) {
    const unsigned ok = index & 15u;
    const unsigned pass = (index >> 4) & 15u;
    bool skip = (index >> 8) != 0;
    unsigned alive = 0;
    for (unsigned bit = 1; bit < 16; bit <<= 1) {
      if (skip) {
        skip = false;
      } else if ((ok & bit) != 0) {  // else the variance is too low: -1, no skip
        if ((pass & bit) == 0) {
          skip = true;
        } else {
          alive |= bit;
        }
      }
    }
    table[index] = static_cast<std::uint8_t>(alive | (skip ? 16u : 0u));
  }
  return table;
}
inline constexpr std::array<std::uint8_t, 512> kFirstStageOutcomes = first_stage_outcomes();

template <typename V>
int cascade_row_simd(const CascadeProgram& p, const std::uint32_t* row, int positions,
                     std::int32_t* hits) {
  constexpr int kLanes = V::kLanesI;
  static_assert(kLanes % 4 == 0);
  const bool lbp = p.type == CascadeFeatureType::lbp;
  const int stage_count = static_cast<int>(p.stages.size());
  int count = 0;
  bool skip = false;  // the previous position was rejected by the first stage
  for (int first = 0; first < positions; first += kLanes) {
    const std::uint32_t* w = row + first;
    const int lanes = std::min(kLanes, positions - first);
    typename V::F factor = V::splatf(1.0f);
    unsigned ok = (1u << lanes) - 1;
    if (!lbp) {
      typename V::M variance_ok;
      V::variance(corner_sum<V>(w, p.norm_offsets),
                  corner_sum<V>(w + p.square_offset, p.norm_offsets), p.norm_area, factor,
                  variance_ok);
      ok &= V::bitsm(variance_ok);
    }
    const auto* w_bytes = reinterpret_cast<const std::uint8_t*>(w);
    const auto run_stage = [&](int s) {
      const ProgramStage& st = p.stages[s];
      const auto first_stump = static_cast<std::size_t>(st.first_weak);
      if (lbp) return V::bitsm(lbp_stage<V>(st, &p.lbp_stumps[first_stump], w_bytes));
      const HaarStump* stumps = &p.haar_stumps[first_stump];
      return V::bitsm(p.integer_weights ? haar_stage<V, true>(st, stumps, w_bytes, factor)
                                        : haar_stage<V, false>(st, stumps, w_bytes, factor));
    };
    const unsigned pass = ok != 0 ? run_stage(0) : 0;
    unsigned alive = 0;
    for (int quad = 0; quad < kLanes; quad += 4) {
      const unsigned outcome =
          kFirstStageOutcomes[((ok >> quad) & 15u) | ((pass >> quad) & 15u) << 4 |
                              unsigned{skip} << 8];
      alive |= (outcome & 15u) << quad;
      skip = (outcome >> 4) != 0;
    }
    for (int stage = 1; alive != 0 && stage < stage_count; ++stage) {
      alive &= run_stage(stage);
    }
    for (int l = 0; alive != 0; ++l, alive >>= 1) {
      if ((alive & 1u) != 0) hits[count++] = (first + l) * p.position_step;
    }
  }
  return count;
}

}  // namespace epipole::vision::kernels
