#pragma once

// The stereo kernels written once over a vocabulary of 16 lanes, as bytes and as 16-bit values
// (simd/neon.hpp, simd/avx2.hpp: Avx2x16). Each gives the same bits as its *_ref in stereo.cpp.
// Disparities go 16 at a time (the range is a multiple of 16): costs and SGM path values in
// bytes, sums in 16-bit lanes.
#include <algorithm>
#include <array>
#include <cstdint>
#include <cstring>
#include <tuple>
#include <type_traits>
#include <utility>

#include "stereo_census.hpp"
#include "stereo_kernels.hpp"
#include "stereo_winner.hpp"

// How many blocks of 16 disparities the loops over the range take at once: eight (a range of
// 128 whole, as kD lets the compiler see) where there are 32 vector registers; one on ARMv7,
// whose 16 would spill (armhf counts: SGM 587 M a pair with one, 596 M with two, 662 M with
// eight).
#if defined(__arm__)
#define EPIPOLE_UNROLL_RANGE _Pragma("GCC unroll 1")
#else
#define EPIPOLE_UNROLL_RANGE _Pragma("GCC unroll 8")
#endif

namespace epipole::vision::kernels {

// Calls run(std::integral_constant<int, kD>) with kD the range when it is one of the common ones
// (64, 128, 256), which have kernels of their own with their loops' trip counts known to the
// compiler, and 0 (the range read at run time) otherwise.
template <typename Run>
void with_common_range(int disparities, Run&& run) {
  switch (disparities) {
    case 64:
      return run(std::integral_constant<int, 64>{});
    case 128:
      return run(std::integral_constant<int, 128>{});
    case 256:
      return run(std::integral_constant<int, 256>{});
    default:
      return run(std::integral_constant<int, 0>{});
  }
}

// Calls run(std::integral_constant<int, kBits>) with the census's bits, kCensusBits or
// kSparseCensusBits (the kernels' contract: they take no other), each with kernels of its own.
template <typename Run>
void with_census_bits(int bits, Run&& run) {
  if (bits == kSparseCensusBits) return run(std::integral_constant<int, kSparseCensusBits>{});
  return run(std::integral_constant<int, kCensusBits>{});
}

// The census's bits in the order of their offsets in the window, row by row. The kernels
// compare in this order: in the table's (the sparse checkerboard first), armhf's census took
// 9 % more instructions.
inline constexpr auto kCensusBitsByRow = [] {
  std::array<int, kCensusBits> order{};
  for (int b = 0; b < kCensusBits; ++b) order[b] = b;
  std::sort(order.begin(), order.end(), [](int a, int b) {
    const CensusOffset p = kCensusOffsets[a], q = kCensusOffsets[b];
    return p.dy != q.dy ? p.dy < q.dy : p.dx < q.dx;
  });
  return order;
}();

// The census's first kBits bits of the 16 pixels from x, whose columns x - 4 .. x + 19 are
// readable, into a row of n pixels from pixel `at`.
template <typename V, CensusLayout kLayout, int kBits>
inline void census_vector(const std::uint8_t* const* rows, int x, std::uint8_t* census, int n,
                          int at) {
  using B = typename V::B;
  B acc[kCensusBytes] = {V::zerob(), V::zerob(), V::zerob(), V::zerob()};
#pragma GCC unroll 31
  for (int i = 0; i < kCensusBits; ++i) {
    const int b = kCensusBitsByRow[i];
    if (b >= kBits) continue;
    const CensusOffset o = kCensusOffsets[b];
    const B a = V::loadb(rows[kCensusRadiusY + o.dy] + x + o.dx);
    const B c = V::loadb(rows[kCensusRadiusY - o.dy] + x - o.dx);
    acc[b / 8] =
        V::set_if_greater(acc[b / 8], a, c, V::splatb(static_cast<std::uint8_t>(1u << (b % 8))));
  }
  if constexpr (kLayout == CensusLayout::words) {
    V::store_interleaved4(census + static_cast<std::ptrdiff_t>(at) * kCensusBytes, acc);
  } else {
    for (int p = 0; p < kCensusBytes; ++p) {
      V::storeb(census + census_byte(kLayout, n, at, p), acc[p]);
    }
  }
}

template <typename V, CensusLayout kLayout, int kBits>
void census_row_bits(const std::uint8_t* const* rows, int width, std::uint8_t* census) {
  constexpr int kLanes = 16;
  constexpr int kR = kCensusRadiusX;
  if (width < kLanes + 2 * kR) {
    for (int x = 0; x < width; ++x)
      set_census(kLayout, census, width, x, census_bits(rows, width, x, kBits));
    return;
  }
  // Interior columns [kR, width - kR); the last vector may overlap the previous one.
  const int end = width - kR;
  for (int x = kR; x < end; x += kLanes) {
    const int at = std::min(x, end - kLanes);
    census_vector<V, kLayout, kBits>(rows, at, census, width, at);
  }
  // The kR border columns on each side: one vector over a copy of the rows with the columns
  // clamped, the same values census_bits reads.
  constexpr int kSpan = kLanes + 2 * kR;
  std::uint8_t copy[7][kSpan];
  const std::uint8_t* copy_rows[7];
  std::uint8_t lanes[kCensusBytes * kLanes];     // the 16 pixels' census, in kLayout
  for (const int first : {0, width - kLanes}) {  // image column of lane 0
    // Columns first - kR .. first + kLanes + kR - 1: the edge column kR times past the border
    // (width >= kSpan).
    for (int r = 0; r < 7; ++r) {
      constexpr int kInside = kSpan - kR;
      if (first == 0) {
        std::memset(copy[r], rows[r][0], kR);
        std::memcpy(copy[r] + kR, rows[r], kInside);
      } else {
        std::memcpy(copy[r], rows[r] + width - kInside, kInside);
        std::memset(copy[r] + kInside, rows[r][width - 1], kR);
      }
      copy_rows[r] = copy[r];
    }
    census_vector<V, kLayout, kBits>(copy_rows, kR, lanes, kLanes, 0);
    const int begin = first == 0 ? 0 : width - kR;
    for (int x = begin; x < begin + kR; ++x) {
      set_census(kLayout, census, width, x, census_at(kLayout, lanes, kLanes, x - first));
    }
  }
}

template <typename V, CensusLayout kLayout>
void census_row_simd(const std::uint8_t* const* rows, int width, int bits, std::uint8_t* census) {
  with_census_bits(bits, [&](auto compared) {
    census_row_bits<V, kLayout, compared.value>(rows, width, census);
  });
}

// The costs of one pixel for 16 disparities: the Hamming distances between its first kBytes
// census bytes (left, splat) and those of 16 pixels of the reversed right planes from `at`.
template <typename V, int kBytes>
inline typename V::B census_distance(const typename V::B* left, const std::uint8_t* const* right,
                                     std::ptrdiff_t at) {
  if constexpr (kBytes == 2) {
    return V::popcount2(V::xorb(left[0], V::loadb(right[0] + at)),
                        V::xorb(left[1], V::loadb(right[1] + at)));
  } else {
    return V::popcount4(
        V::xorb(left[0], V::loadb(right[0] + at)), V::xorb(left[1], V::loadb(right[1] + at)),
        V::xorb(left[2], V::loadb(right[2] + at)), V::xorb(left[3], V::loadb(right[3] + at)));
  }
}

// The bytes of a census of kBits bits.
template <int kBits>
constexpr int kBytesOf = (kBits + 7) / 8;

// One pixel's census (its first kBits bits) against 16 of the reversed right row's, in either
// layout: what the cost row needs of it.
template <typename V, CensusLayout kLayout, int kBits>
class CensusPixel;

template <typename V, int kBits>
class CensusPixel<V, CensusLayout::planes, kBits> {
  static constexpr int kBytes = kBytesOf<kBits>;

 public:
  CensusPixel(const std::uint8_t* left, const std::uint8_t* right, int width, int disparities) {
    // The plane pointers in this object's members, not read through the caller's arrays: the
    // byte stores into the cost row may alias those, and the compiler would load them again
    // after each one.
#pragma GCC unroll 4
    for (int p = 0; p < kBytes; ++p) {
      left_[p] = left + static_cast<std::ptrdiff_t>(p) * width;
      right_[p] = right + static_cast<std::ptrdiff_t>(p) * (width + disparities);
    }
  }
  void load(int x) {
#pragma GCC unroll 4
    for (int p = 0; p < kBytes; ++p) l_[p] = V::load_splatb(left_[p] + x);
  }
  // The distances to right pixels k .. k + 15.
  typename V::B distance(std::ptrdiff_t k) const {
    return census_distance<V, kBytes>(l_, right_, k);
  }

 private:
  const std::uint8_t* left_[kBytes];
  const std::uint8_t* right_[kBytes];
  typename V::B l_[kBytes];
};

template <typename V, int kBits>
class CensusPixel<V, CensusLayout::words, kBits> {
 public:
  CensusPixel(const std::uint8_t* left, const std::uint8_t* right, int, int)
      : left_(left), right_(right) {}
  void load(int x) {
    const std::uint8_t* word = left_ + static_cast<std::ptrdiff_t>(x) * kCensusBytes;
    if constexpr (kBytesOf<kBits> == 2) {
      l_[0] = V::load_splatb(word);
      l_[1] = V::load_splatb(word + 1);
    } else {
      l_[0] = V::load_splat_word(word);
    }
  }
  typename V::B distance(std::ptrdiff_t k) const {
    const std::uint8_t* words = right_ + k * kCensusBytes;
    if constexpr (kBytesOf<kBits> == 2) {
      return V::popcount_low2_words16(l_[0], l_[1], words);
    } else {
      return V::popcount_words16(l_[0], words);
    }
  }

 private:
  const std::uint8_t* left_;
  const std::uint8_t* right_;
  typename V::B l_[2];
};

// Row costs, pixel by pixel: the blocks of 16 disparities inside the image first, then the one
// that reaches beyond its left border (d > x), where the cost is the most, then those wholly
// beyond it, which are that maximum alone. kD: the range when fixed at compile time (0:
// disparities). kBits: the census bits compared.
template <typename V, CensusLayout kLayout, int kBits, int kD = 0>
void cost_row_range(const std::uint8_t* left, const std::uint8_t* right, int width, int disparities,
                    std::uint8_t* cost) {
  using B = typename V::B;
  CensusPixel<V, kLayout, kBits> pixel(left, right, width, disparities);
  const B max_cost = V::splatb(kBits);
  for (int x = 0; x < width; ++x) {
    pixel.load(x);
    const std::ptrdiff_t k = width - 1 - x;
    std::uint8_t* out = cost + static_cast<std::ptrdiff_t>(x) * disparities;
    // Block d lies inside when its last disparity does: d + 15 <= x.
    if (kD != 0 && x >= kD - 1) {
      EPIPOLE_UNROLL_RANGE
      for (int d = 0; d < kD; d += 16) V::storeb(out + d, pixel.distance(k + d));
      continue;
    }
    const int inside = x < 15 ? 0 : std::min(disparities, (x - 15) / 16 * 16 + 16);
    int d = 0;
    for (; d < inside; d += 16) V::storeb(out + d, pixel.distance(k + d));
    if (d < disparities && d <= x) {
      const B beyond = V::gtb(V::addb(V::iotab(), V::splatb(static_cast<std::uint8_t>(d))),
                              V::splatb(static_cast<std::uint8_t>(x)));
      V::storeb(out + d, V::maxb(pixel.distance(k + d), V::andb(beyond, max_cost)));
      d += 16;
    }
    for (; d < disparities; d += 16) V::storeb(out + d, max_cost);
  }
}

template <typename V, CensusLayout kLayout>
void cost_row_simd(const std::uint8_t* left, const std::uint8_t* right, int width, int disparities,
                   int bits, std::uint8_t* cost) {
  with_census_bits(bits, [&](auto compared) {
    with_common_range(disparities, [&](auto range) {
      cost_row_range<V, kLayout, compared.value, range.value>(left, right, width, disparities,
                                                              cost);
    });
  });
}

// The disparities of 16 lanes as WtaPixels keeps them: bytes where the vocabulary narrows a
// mask of 16-bit lanes to bytes in one instruction (narrow_maskh: NEON), 16-bit lanes
// otherwise.
template <typename V, bool kBytes = requires(typename V::H mask) {
  V::narrow_maskh(mask);
}
> struct DisparityLanes {
  using T = typename V::B;
  using Value = std::uint8_t;
  static T iota() { return V::iotab(); }
  static T splat(Value v) { return V::splatb(v); }
  static T add(T a, T b) { return V::addb(a, b); }
  static T select(typename V::H mask, T a, T b) { return V::selectb(V::narrow_maskh(mask), a, b); }
  static T load(const Value* p) { return V::loadb(p); }
  static void store(Value* p, T v) { V::storeb(p, v); }
  static typename V::H widen(T v) { return V::widen(v); }
  static T reverse(T v) requires requires { V::reverseb(v); }
  { return V::reverseb(v); }
};
template <typename V>
struct DisparityLanes<V, false> {
  using T = typename V::H;
  using Value = std::uint16_t;
  static T iota() { return V::iotah(); }
  static T splat(Value v) { return V::splath(v); }
  static T add(T a, T b) { return V::addh(a, b); }
  static T select(T mask, T a, T b) { return V::selecth(mask, a, b); }
  static T load(const Value* p) { return V::loadh(p); }
  static void store(Value* p, T v) { V::storeh(p, v); }
  static T widen(T v) { return v; }
};

// Winner take all, one pixel at a time in increasing x (wta_row_ref defines the result).
// The right image's candidates, a (cost, disparity) pair for each right pixel xr, are kept in
// reverse order (entry width - 1 - xr), so that pixel x's disparities d .. d + 15 meet right
// pixels x - d .. x - d - 15 at the consecutive entries width - 1 - x + d ..: one load and store
// a block, no shift (RightWinners::exact, SGM's). Entries past width - 1 (right pixels left of
// the image) are written and never read. The disparities need no first value: every sum is below
// kNoCost (SGM's at most 5 * 255), so a right pixel's first candidate,
// at d = 0, replaces its kNoCost. kD: the range when fixed at compile time (0: the constructor's).
// kSmallSums: every sum is below 2048 (SGM's), so a vocabulary's min_first_small may find the
// winner.
//
// The disparities, at most 255, are kept as bytes where the vocabulary allows
// (DisparityLanes): the right image's, and each lane's best of the pixel. A block then costs one
// load, select and store of them rather than two each, and one add for the next block's
// disparities.
//
// kRight: how the right image's winners are found (RightWinners). That window is exact's; with
// left_winners each pixel's winner, once known, goes to its right pixel alone, and the window
// holds each right pixel's lowest winning cost so far (entry xr).
template <typename V, int kD = 0, bool kSmallSums = false,
          RightWinners kRight = RightWinners::exact>
class WtaPixels {
  using H = typename V::H;
  using Lanes = DisparityLanes<V>;
  using Disparity = typename Lanes::Value;
  static constexpr bool kExact = kRight == RightWinners::exact;

 public:
  WtaPixels(const WtaRow& row, int width, int disparities)
      : row_(row),
        width_(width),
        disparities_(disparities),
        ratio_(uniqueness_ratio(row.uniqueness)),
        cost_(row.window),
        disp_(reinterpret_cast<Disparity*>(row.window + width + disparities)) {
    // 16 at a time (the last 16 may overlap the ones before): kNoCost in every entry, and for
    // left_winners no right winner yet.
    const auto fill = [](std::uint16_t* p, int n, std::uint16_t v) {
      for (int i = 0; i < n; i += 16) V::storeh(p + std::min(i, n - 16), V::splath(v));
    };
    if constexpr (kExact) {
      fill(cost_, width + disparities, kNoCost);
    } else {
      fill(cost_, width, kNoCost);
      fill(reinterpret_cast<std::uint16_t*>(row.right_best), width, 0xFFFF);  // -1
    }
  }

  // The winner of pixel x. sums(d) gives the sums of disparities d .. d + 15 and must have
  // stored them at s + d, where the sub-pixel step reads the three around the winner.
  //
  // Uniqueness and confidence need the lowest sum outside best - 1 .. best + 1. Each lane keeps
  // its smallest sum, where it is, and its second smallest; a lane whose smallest is one of
  // those three (they lie in three different lanes) gives its second smallest instead, which
  // is nowhere near the winner (16 disparities away at least). The pixel is unique when that
  // sum is not below the limit: then every sum below the limit is at best - 1 .. best + 1, as
  // wta_row_ref counts them.
  template <typename Sums>
  [[gnu::always_inline]] inline void pixel(int x, const std::uint16_t* s, Sums&& sums) {
    pixel(x, s, std::forward<Sums>(sums), kD != 0 ? kD : disparities_);
  }

  // The same with the blocks of 16 disparities from `end` on left out: the caller knows that
  // their sums are the largest of the pixel's, at least as large as its smallest and second
  // smallest in each lane, and that their right pixels lie left of the image (d > x).
  template <typename Sums>
  [[gnu::always_inline]] inline void pixel(int x, const std::uint16_t* s, Sums&& sums, int end) {
    const int D = kD != 0 ? kD : disparities_;
    H m = V::splath(kNoCost);
    H second = V::splath(kNoCost);
    std::uint16_t* const cost = cost_ + (width_ - 1 - x);
    Disparity* const disp = disp_ + (width_ - 1 - x);
    const auto sixteen = Lanes::splat(16);
    auto index = Lanes::iota();
    auto best_index = Lanes::splat(0);
    EPIPOLE_UNROLL_RANGE
    for (int d = 0; d < end; d += 16) {
      const H v = sums(d);
      best_index = Lanes::select(V::gth(m, v), index, best_index);
      second = V::minh(second, V::maxh(m, v));
      m = V::minh(m, v);
      if constexpr (kExact) {
        const H old_cost = V::loadh(cost + d);
        V::storeh(cost + d, V::minh(old_cost, v));
        Lanes::store(disp + d, Lanes::select(V::gth(old_cost, v), index, Lanes::load(disp + d)));
      }
      index = Lanes::add(index, sixteen);
    }
    const H m_index = Lanes::widen(best_index);

    int min_cost;
    int best;
    if constexpr (kSmallSums && requires { V::min_first_small(m, m_index); }) {
      std::tie(min_cost, best) = V::min_first_small(m, m_index);
    } else {
      min_cost = V::hminh(m);
      best = V::hminh(V::selecth(V::eqh(m, V::splath(static_cast<std::uint16_t>(min_cost))),
                                 m_index, V::splath(0xFFFF)));
    }
    // m_index - (best - 1) is 0, 1 or 2 (as unsigned 16 bits) at the three.
    const H offset = V::subh(m_index, V::splath(static_cast<std::uint16_t>(best - 1)));
    const H near = V::eqh(V::minh(offset, V::splath(2)), offset);
    const int others = V::hminh(V::selecth(near, second, m));
    const int limit = std::min(uniqueness_limit(min_cost, ratio_), static_cast<int>(kNoCost));
    const int winner = others >= limit ? best : -1;
    store_winner(row_, x, winner, s, D, row_.confidence != nullptr ? others : kNoCost);
    if constexpr (!kExact) {
      // Pixels x in increasing order: among equal costs at a right pixel, the smallest d stays.
      if (winner >= 0 && winner <= x && min_cost < cost_[x - winner]) {
        cost_[x - winner] = static_cast<std::uint16_t>(min_cost);
        row_.right_best[x - winner] = static_cast<std::int16_t>(winner);
      }
    }
  }

  // After the last pixel: every right pixel's winner (width >= 16).
  void finish() {
    if constexpr (!kExact) {
      return;  // each pixel gave its own
    } else if constexpr (requires(typename Lanes::T v) { Lanes::reverse(v); }) {
      // 16 at a time; the last 16 may overlap the ones before.
      for (int xr0 = 0; xr0 < width_; xr0 += 16) {
        const int xr = std::min(xr0, width_ - 16);
        const auto winners = Lanes::reverse(Lanes::load(disp_ + (width_ - 16 - xr)));
        V::storeh(reinterpret_cast<std::uint16_t*>(row_.right_best + xr), Lanes::widen(winners));
      }
    } else {
      for (int xr = 0; xr < width_; ++xr) {
        row_.right_best[xr] = static_cast<std::int16_t>(disp_[width_ - 1 - xr]);
      }
    }
  }

 private:
  WtaRow row_;
  int width_;
  int disparities_;
  std::uint32_t ratio_;
  std::uint16_t* cost_;
  Disparity* disp_;
};

// One path step for 16 disparities at d: c + min(p[d], p[d-1] + P1, p[d+1] + P1,
// min_prev + P2) - min_prev, in bytes. The saturating adds are exact where it matters: a sum
// that saturates is above p[d] <= 255 and cannot be the minimum; the result is at most
// 31 + P2 <= 255.
template <typename V>
inline typename V::B sgm_step(typename V::B c, const std::uint8_t* p, typename V::B p1,
                              typename V::B min_p2, typename V::B min_prev) {
  const typename V::B best = V::minb(V::minb(V::loadb(p), min_p2),
                                     V::addsb(V::minb(V::loadb(p - 1), V::loadb(p + 1)), p1));
  return V::addb(V::subb(best, min_prev), c);
}

// The first of an SGM row's two passes: right to left, with the three paths from the previous
// row, the sums of four paths into r.sums. kD: the range when fixed at compile time (0: r's).
template <typename V, int kD = 0>
void sgm_first_pass_simd(const SgmRow& r) {
  using B = typename V::B;
  using H = typename V::H;
  const int D = kD != 0 ? kD : r.disparities;
  const int width = r.width;
  const B p1 = V::splatb(static_cast<std::uint8_t>(r.p1));
  const B p2 = V::splatb(static_cast<std::uint8_t>(r.p2));
  std::uint8_t* h[2];
  sgm_horizontal_rows(r, h);
  // Where pixel 0's downward paths are (SgmDownPaths): pixel x's are x * stride bytes (x
  // minima) on. In locals, so that the byte stores below do not make the compiler load them
  // again from r.
  const std::ptrdiff_t stride = static_cast<std::ptrdiff_t>(D) + 32;
  const SgmDownPaths origin(r, 0);
  const std::uint8_t* prev[3];
  std::uint8_t* cur[3];
  const std::uint8_t* prev_min[3];
  std::uint8_t* cur_min[3];
#pragma GCC unroll 3
  for (int k = 0; k < 3; ++k) {
    prev[k] = origin.prev[k];
    cur[k] = origin.cur[k];
    prev_min[k] = origin.prev_min_at[k];
    cur_min[k] = r.cur_min[k] + 1;
  }
  const std::uint8_t* const cost = r.cost;
  std::uint16_t* const sums = r.sums;
  B h_prev = V::zerob();
  for (int x = width - 1; x >= 0; --x) {
    const std::ptrdiff_t at = static_cast<std::ptrdiff_t>(x) * stride;
    const std::uint8_t* c = cost + static_cast<std::ptrdiff_t>(x) * D;
    std::uint16_t* s = sums + static_cast<std::ptrdiff_t>(x) * D;
    const std::uint8_t* p[3];
    std::uint8_t* q[3];
    B min_prev[3];
    B min_p2[3];
    B mins[4];
#pragma GCC unroll 3
    for (int k = 0; k < 3; ++k) {
      p[k] = prev[k] + at;
      q[k] = cur[k] + at;
      min_prev[k] = V::load_splatb(prev_min[k] + x);
      min_p2[k] = V::addsb(min_prev[k], p2);  // min_prev + P2, saturated to a byte
      mins[k] = V::splatb(0xFF);
    }
    mins[3] = V::splatb(0xFF);
    const B h_p2 = V::addsb(h_prev, p2);
    EPIPOLE_UNROLL_RANGE
    for (int d = 0; d < D; d += 16) {
      const B c_d = V::loadb(c + d);
      const B rl = sgm_step<V>(c_d, h[0] + d, p1, h_p2, h_prev);
      V::storeb(h[1] + d, rl);
      mins[3] = V::minb(mins[3], rl);
      H sum = V::widen(rl);
#pragma GCC unroll 3
      for (int k = 0; k < 3; ++k) {
        const B v = sgm_step<V>(c_d, p[k] + d, p1, min_p2[k], min_prev[k]);
        V::storeb(q[k] + d, v);
        mins[k] = V::minb(mins[k], v);
        sum = V::addw(sum, v);
      }
      V::storeh(s + d, sum);
    }
#pragma GCC unroll 3
    for (int k = 0; k < 3; ++k) cur_min[k][x] = V::hminb(mins[k]);
    h_prev = V::splatb(V::hminb(mins[3]));
    std::swap(h[0], h[1]);
  }
}

// The second pass: left to right, the fifth path added to the sums, then the winner of each
// pixel. kD as in sgm_first_pass_simd.
template <typename V, int kD = 0>
void sgm_second_pass_simd(const SgmRow& r) {
  using B = typename V::B;
  using H = typename V::H;
  const int D = kD != 0 ? kD : r.disparities;
  const int width = r.width;
  const B p1 = V::splatb(static_cast<std::uint8_t>(r.p1));
  const B p2 = V::splatb(static_cast<std::uint8_t>(r.p2));
  const std::uint8_t* const cost = r.cost;  // in locals: see sgm_first_pass_simd
  std::uint16_t* const sums = r.sums;
  std::uint8_t* h[2];
  sgm_horizontal_rows(r, h);
  WtaPixels<V, kD> wta(r.wta, width, D);
  B h_prev = V::zerob();
  for (int x = 0; x < width; ++x) {
    const std::uint8_t* c = cost + static_cast<std::ptrdiff_t>(x) * D;
    std::uint16_t* s = sums + static_cast<std::ptrdiff_t>(x) * D;
    const B h_p2 = V::addsb(h_prev, p2);  // min_prev + P2, saturated to a byte
    B m = V::splatb(0xFF);
    wta.pixel(x, s, [&](int d) {
      const B lr = sgm_step<V>(V::loadb(c + d), h[0] + d, p1, h_p2, h_prev);
      V::storeb(h[1] + d, lr);
      m = V::minb(m, lr);
      const H sum = V::addw(V::loadh(s + d), lr);
      V::storeh(s + d, sum);
      return sum;
    });
    h_prev = V::splatb(V::hminb(m));
    std::swap(h[0], h[1]);
  }
  wta.finish();
}

template <typename V, int kD>
void sgm_row_fixed(const SgmRow& r) {
  sgm_first_pass_simd<V, kD>(r);
  sgm_second_pass_simd<V, kD>(r);
}

template <typename V>
void sgm_row_simd(const SgmRow& r) {
  with_common_range(r.disparities, [&](auto range) { sgm_row_fixed<V, range.value>(r); });
}

template <typename V>
void box_columns_simd(std::uint16_t* sums, const std::uint8_t* add, const std::uint8_t* sub,
                      int n) {
  int i = 0;
  if (add != nullptr && sub != nullptr) {
    for (; i + 16 <= n; i += 16) {
      V::storeh(sums + i, V::subh(V::addw(V::loadh(sums + i), V::loadb(add + i)),
                                  V::widen(V::loadb(sub + i))));
    }
    for (; i < n; ++i) sums[i] = static_cast<std::uint16_t>(sums[i] + add[i] - sub[i]);
  } else if (add != nullptr) {
    for (; i + 16 <= n; i += 16)
      V::storeh(sums + i, V::addw(V::loadh(sums + i), V::loadb(add + i)));
    for (; i < n; ++i) sums[i] = static_cast<std::uint16_t>(sums[i] + add[i]);
  } else if (sub != nullptr) {
    for (; i + 16 <= n; i += 16) {
      V::storeh(sums + i, V::subh(V::loadh(sums + i), V::widen(V::loadb(sub + i))));
    }
    for (; i < n; ++i) sums[i] = static_cast<std::uint16_t>(sums[i] - sub[i]);
  }
}

// Block matching: one column for row y, 16 disparities from d (column += entering - leaving;
// the pointers are the column's D values in each).
template <typename V, bool kEnters, bool kLeaves>
[[gnu::always_inline]] inline typename V::H bm_column(std::uint16_t* column,
                                                      const std::uint8_t* entering,
                                                      const std::uint8_t* leaving, int d) {
  typename V::H v = V::loadh(column + d);
  if constexpr (kEnters) v = V::addw(v, V::loadb(entering + d));
  if constexpr (kLeaves) v = V::subh(v, V::widen(V::loadb(leaving + d)));
  V::storeh(column + d, v);
  return v;
}

// Block matching's pixel x = 0: columns 0..R updated, its box summed into r.sums.
template <typename V, bool kEnters, bool kLeaves, int kD, typename Wta>
[[gnu::always_inline]] inline void bm_first_pixel(const BmRow& r, Wta& wta) {
  const int D = kD != 0 ? kD : r.disparities;
  const int R = r.radius;
  const auto offset = [&](int c) { return static_cast<std::ptrdiff_t>(c) * D; };
  const auto update = [&](int c, int d) {
    return bm_column<V, kEnters, kLeaves>(r.columns + offset(c),
                                          kEnters ? r.entering + offset(c) : nullptr,
                                          kLeaves ? r.leaving + offset(c) : nullptr, d);
  };
  for (int c = 0; c < R; ++c) {
    for (int d = 0; d < D; d += 16) update(c, d);
  }
  wta.pixel(0, r.sums, [&](int d) {
    typename V::H acc = update(R, d);
    for (int c = 0; c < R; ++c) acc = V::addh(acc, V::loadh(r.columns + offset(c) + d));
    V::storeh(r.sums + d, acc);
    return acc;
  });
}

// Block matching's pixels from x on (after the first and the left band's), their box sums in
// `sums`: column x + R enters (updated then) and column x - R - 1 leaves (`zero` before the first
// column); in the last R pixels no column enters. Written out, not through bm_row_sweep's
// band_pixel lambda: through it GCC kept the pointers on the stack (aarch64 block matching
// 172.3 M a pair -> 180 M).
template <typename V, bool kEnters, bool kLeaves, int kD, typename Wta>
[[gnu::always_inline]] inline void bm_row_pixels(const BmRow& r, Wta& wta,
                                                 const std::uint16_t* zero, int x) {
  using H = typename V::H;
  const int W = r.width;
  const int D = kD != 0 ? kD : r.disparities;
  const int R = r.radius;
  std::uint16_t* const sums = r.sums;
  const auto offset = [&](int c) { return static_cast<std::ptrdiff_t>(c) * D; };
  for (; x < W - R; ++x) {
    const std::uint16_t* leaves = x - R - 1 >= 0 ? r.columns + offset(x - R - 1) : zero;
    std::uint16_t* column = r.columns + offset(x + R);
    const std::uint8_t* entering = kEnters ? r.entering + offset(x + R) : nullptr;
    const std::uint8_t* leaving = kLeaves ? r.leaving + offset(x + R) : nullptr;
    wta.pixel(x, sums, [&](int d) {
      const H acc = V::subh(
          V::addh(V::loadh(sums + d), bm_column<V, kEnters, kLeaves>(column, entering, leaving, d)),
          V::loadh(leaves + d));
      V::storeh(sums + d, acc);
      return acc;
    });
  }
  for (x = std::max(W - R, 1); x < W; ++x) {
    const std::uint16_t* leaves = x - R - 1 >= 0 ? r.columns + offset(x - R - 1) : zero;
    wta.pixel(x, sums, [&](int d) {
      const H acc = V::subh(V::loadh(sums + d), V::loadh(leaves + d));
      V::storeh(sums + d, acc);
      return acc;
    });
  }
}

// One row of block matching in one sweep: column x + r updated just before the box of x needs
// it, the box of x from the box of x - 1, its winner.
template <typename V, bool kEnters, bool kLeaves, int kD = 0>
void bm_row_sweep(const BmRow& r) {
  using H = typename V::H;
  const int W = r.width;
  const int D = kD != 0 ? kD : r.disparities;
  const int R = r.radius;
  std::uint16_t* const sums = r.sums;
  const auto offset = [&](int c) { return static_cast<std::ptrdiff_t>(c) * D; };
  // The entering and leaving costs of column c (null when there is no such row).
  const auto entering_at = [&](int c) { return kEnters ? r.entering + offset(c) : nullptr; };
  const auto leaving_at = [&](int c) { return kLeaves ? r.leaving + offset(c) : nullptr; };
  constexpr bool kSmallSums = false;  // up to 21 * 21 * 16
  WtaPixels<V, kD, kSmallSums, RightWinners::left_winners> wta(r.wta, W, D);
  bm_first_pixel<V, kEnters, kLeaves, kD>(r, wta);
  // Column x + R enters, column x - R - 1 leaves (zeros before the first column).
  std::uint16_t* const zero = sums + D;
  std::fill_n(zero, D, std::uint16_t{0});
  // The left band's pixels (below). Written out again for the others (bm_row_pixels): through
  // this lambda GCC kept their pointers on the stack (aarch64 block matching 172.3 M a pair ->
  // 180 M).
  const auto band_pixel = [&](int x, int end) __attribute__((always_inline)) {
    const std::uint16_t* leaves = x - R - 1 >= 0 ? r.columns + offset(x - R - 1) : zero;
    std::uint16_t* column = r.columns + offset(x + R);
    const std::uint8_t* entering = entering_at(x + R);
    const std::uint8_t* leaving = leaving_at(x + R);
    wta.pixel(
        x, sums,
        [&](int d) {
          const H acc = V::subh(V::addh(V::loadh(sums + d), bm_column<V, kEnters, kLeaves>(
                                                                column, entering, leaving, d)),
                                V::loadh(leaves + d));
          V::storeh(sums + d, acc);
          return acc;
        },
        end);
  };
  // Between the first and last rows (BmRow's promise) a pixel x of the left band takes only the
  // blocks of 16 disparities that reach x + R: in the others every cost of its box is the
  // cost row's maximum (max_cost), so their columns hold 2R + 1 of it and never change, their box
  // sums the most any box can (no winner, no second smallest: WtaPixels::pixel) and their right
  // pixels lie left of the image. At 640 x 480 with 128 disparities and block 7: 8 % of the blocks.
  constexpr bool kSkip = kEnters && kLeaves && kD != 0;
  int current = D;  // the blocks below this one have the sums of the pixel before
  // The blocks current .. end - 1 counted again from pixel x: their sums at x - 1, the columns of
  // the image in x - 1 - R .. x - 1 + R at their most.
  const auto count_blocks = [&](int x, int end) {
    if (current >= end) return;
    const int box_columns = std::min(x - 1 + R, W - 1) - std::max(x - 1 - R, 0) + 1;
    std::fill(sums + current, sums + end,
              static_cast<std::uint16_t>(box_columns * (2 * R + 1) * r.max_cost));
    current = end;
  };
  int x = 1;
  if constexpr (kSkip) {
    // The pixels that take the blocks below kEnd: x + R < kEnd.
    const auto band = [&]<int kEnd>(std::integral_constant<int, kEnd>) {
      const int stop = std::min(W - R, kEnd - R);
      if (x >= stop) return;
      count_blocks(x, kEnd);
      for (; x < stop; ++x) band_pixel(x, kEnd);
      current = kEnd;
    };
    // (With R = 0 a winner could be a block's last disparity, and its sub-pixel step would read
    // the next block's stale sums.)
    if (R > 0) {
      [&]<int... kBlock>(std::integer_sequence<int, kBlock...>) {
        (band(std::integral_constant<int, 16 * (kBlock + 1)>{}), ...);
      }
      (std::make_integer_sequence<int, kD / 16 - 1>{});
    }
  }
  count_blocks(x, D);
  bm_row_pixels<V, kEnters, kLeaves, kD>(r, wta, zero, x);
  wta.finish();
}

template <typename V>
void bm_row_simd(const BmRow& r) {
  // The rows inside the image, each with a row entering the box and one leaving it: the common
  // ranges with their loops' trip counts known to the compiler.
  if (r.entering != nullptr && r.leaving != nullptr) {
    with_common_range(r.disparities,
                      [&](auto range) { bm_row_sweep<V, true, true, range.value>(r); });
    return;
  }
  if (r.entering != nullptr) {
    bm_row_sweep<V, true, false>(r);
  } else {
    r.leaving != nullptr ? bm_row_sweep<V, false, true>(r) : bm_row_sweep<V, false, false>(r);
  }
}

}  // namespace epipole::vision::kernels
