#include "epipole/vision/stereo.hpp"

#include <algorithm>
#include <bit>
#include <cstdlib>
#include <cstring>

#include "epipole/core/error.hpp"
#include "epipole/core/race_annotations.hpp"
#include "epipole/vision/disparity_filters.hpp"
#include "kernel_set.hpp"
#include "stereo_census.hpp"
#include "stereo_kernels.hpp"
#include "stereo_winner.hpp"

namespace epipole::vision {

namespace kernels {

StereoKernels stereo_kernels_neon();
StereoKernels stereo_kernels_avx2();

std::uint32_t census_bits(const std::uint8_t* const* rows, int width, int x, int bits) {
  std::uint32_t census = 0;
  for (int b = 0; b < bits; ++b) {
    const CensusOffset o = kCensusOffsets[b];
    const int xa = std::clamp(x + o.dx, 0, width - 1);
    const int xc = std::clamp(x - o.dx, 0, width - 1);
    if (rows[kCensusRadiusY + o.dy][xa] > rows[kCensusRadiusY - o.dy][xc]) census |= 1u << b;
  }
  return census;
}

void census_row_ref(const std::uint8_t* const* rows, int width, int bits, std::uint8_t* census) {
  for (int x = 0; x < width; ++x) {
    set_census(CensusLayout::planes, census, width, x, census_bits(rows, width, x, bits));
  }
}

void cost_row_ref(const std::uint8_t* left, const std::uint8_t* right, int width, int disparities,
                  int bits, std::uint8_t* cost) {
  const std::uint32_t compared = (1u << bits) - 1;
  for (int x = 0; x < width; ++x) {
    const std::uint32_t l = census_at(CensusLayout::planes, left, width, x);
    for (int d = 0; d < disparities; ++d) {
      const int k = width - 1 - x + d;
      const int differ = std::popcount(
          (l ^ census_at(CensusLayout::planes, right, width + disparities, k)) & compared);
      cost[static_cast<std::ptrdiff_t>(x) * disparities + d] =
          static_cast<std::uint8_t>(d > x ? bits : differ);
    }
  }
}

void wta_row_ref(const std::uint16_t* sums, int width, int D, const WtaRow& wta,
                 RightWinners right) {
  const std::uint32_t ratio = uniqueness_ratio(wta.uniqueness);
  for (int x = 0; x < width; ++x) {
    const std::uint16_t* s = sums + static_cast<std::ptrdiff_t>(x) * D;
    int best = 0;
    for (int d = 0; d < D; ++d) {
      if (s[d] < s[best]) best = d;
    }
    const int min_cost = s[best];
    const int limit = uniqueness_limit(min_cost, ratio);
    bool unique = true;
    int other = kNoCost;
    for (int d = 0; d < D; ++d) {
      if (std::abs(d - best) <= 1) continue;
      if (s[d] < limit) unique = false;
      other = std::min<int>(other, s[d]);
    }
    store_winner(wta, x, unique ? best : -1, s, D, other);
  }
  if (right == RightWinners::left_winners) {
    std::uint16_t* const lowest = wta.window;  // of the winners landing on each xr
    std::fill_n(lowest, width, kNoCost);
    std::fill_n(wta.right_best, width, std::int16_t{-1});
    for (int x = 0; x < width; ++x) {
      const int d = wta.best[x];
      if (d < 0) continue;
      const std::uint16_t cost = sums[static_cast<std::ptrdiff_t>(x) * D + d];
      if (cost < lowest[x - d]) {
        lowest[x - d] = cost;
        wta.right_best[x - d] = static_cast<std::int16_t>(d);
      }
    }
    return;
  }
  for (int xr = 0; xr < width; ++xr) {
    int best = 0;
    for (int d = 1; d < std::min(D, width - xr); ++d) {
      if (sums[static_cast<std::ptrdiff_t>(xr + d) * D + d] <
          sums[static_cast<std::ptrdiff_t>(xr + best) * D + best]) {
        best = d;
      }
    }
    wta.right_best[xr] = static_cast<std::int16_t>(best);
  }
}

namespace {
// One path step: c + min(p[d], p[d-1] + P1, p[d+1] + P1, min_prev + P2) - min_prev.
int sgm_step(int c, const std::uint8_t* p, int d, int p1, int p2, int min_prev) {
  const int best = std::min({static_cast<int>(p[d]), p[d - 1] + p1, p[d + 1] + p1, min_prev + p2});
  return c + best - min_prev;
}

// One horizontal path over the row (dx = +1: left to right), its values added to sums.
void sgm_horizontal_ref(const SgmRow& r, int dx) {
  const int D = r.disparities;
  std::uint8_t* h[2];
  sgm_horizontal_rows(r, h);
  int h_min = 0;
  for (int i = 0; i < r.width; ++i) {
    const int x = dx > 0 ? i : r.width - 1 - i;
    const std::uint8_t* c = r.cost + static_cast<std::ptrdiff_t>(x) * D;
    std::uint16_t* s = r.sums + static_cast<std::ptrdiff_t>(x) * D;
    int next_h_min = 0xFF;
    for (int d = 0; d < D; ++d) {
      const int v = sgm_step(c[d], h[0], d, r.p1, r.p2, h_min);
      h[1][d] = static_cast<std::uint8_t>(v);
      next_h_min = std::min(next_h_min, v);
      s[d] = static_cast<std::uint16_t>(s[d] + v);
    }
    h_min = next_h_min;
    std::swap(h[0], h[1]);
  }
}
}  // namespace

void sgm_row_ref(const SgmRow& r) {
  const int D = r.disparities;
  for (int x = 0; x < r.width; ++x) {
    const std::uint8_t* c = r.cost + static_cast<std::ptrdiff_t>(x) * D;
    std::uint16_t* s = r.sums + static_cast<std::ptrdiff_t>(x) * D;
    for (int d = 0; d < D; ++d) s[d] = 0;
    const SgmDownPaths paths(r, x);
    for (int k = 0; k < 3; ++k) {
      const std::uint8_t* p = paths.prev[k];
      const int min_prev = paths.prev_min[k];
      std::uint8_t* q = paths.cur[k];
      int m = 0xFF;
      for (int d = 0; d < D; ++d) {
        const int v = sgm_step(c[d], p, d, r.p1, r.p2, min_prev);
        q[d] = static_cast<std::uint8_t>(v);
        m = std::min(m, v);
        s[d] = static_cast<std::uint16_t>(s[d] + v);
      }
      r.cur_min[k][x + 1] = static_cast<std::uint8_t>(m);
    }
  }
  sgm_horizontal_ref(r, 1);
  sgm_horizontal_ref(r, -1);
  wta_row_ref(r.sums, r.width, D, r.wta, RightWinners::exact);
}

void box_columns_ref(std::uint16_t* sums, const std::uint8_t* add, const std::uint8_t* sub, int n) {
  for (int i = 0; i < n; ++i) {
    int v = sums[i];
    if (add != nullptr) v += add[i];
    if (sub != nullptr) v -= sub[i];
    sums[i] = static_cast<std::uint16_t>(v);
  }
}

void box_wta_ref(const std::uint16_t* columns, int width, int D, int radius, std::uint16_t* sums,
                 const WtaRow& wta) {
  for (int x = 0; x < width; ++x) {
    for (int d = 0; d < D; ++d) {
      int v = 0;
      for (int i = std::max(0, x - radius); i <= std::min(width - 1, x + radius); ++i) {
        v += columns[static_cast<std::ptrdiff_t>(i) * D + d];
      }
      sums[static_cast<std::ptrdiff_t>(x) * D + d] = static_cast<std::uint16_t>(v);
    }
  }
  wta_row_ref(sums, width, D, wta, RightWinners::left_winners);
}

void bm_row_ref(const BmRow& r) {
  box_columns_ref(r.columns, r.entering, r.leaving, r.width * r.disparities);
  box_wta_ref(r.columns, r.width, r.disparities, r.radius, r.sums, r.wta);
}

namespace {
// dst[n - 1 - i] = src[i], eight bytes at a time.
void reverse_bytes(const std::uint8_t* src, int n, std::uint8_t* dst) {
  int i = 0;
  for (; i + 8 <= n; i += 8) {
    std::uint64_t v;
    std::memcpy(&v, src + i, 8);
    v = __builtin_bswap64(v);
    std::memcpy(dst + n - 8 - i, &v, 8);
  }
  for (; i < n; ++i) dst[n - 1 - i] = src[i];
}
}  // namespace

void reverse_census(CensusLayout layout, const std::uint8_t* census, int n, int padded,
                    std::uint8_t* reversed) {
  if (layout == CensusLayout::planes) {
    for (std::ptrdiff_t p = 0; p < kCensusBytes; ++p) {
      reverse_bytes(census + p * n, n, reversed + p * padded);
    }
    return;
  }
  // Two words at a time: swapping the halves of their 8 bytes swaps them.
  int i = 0;
  for (; i + 2 <= n; i += 2) {
    std::uint64_t pair;
    std::memcpy(&pair, census + kCensusBytes * i, sizeof pair);
    pair = std::rotr(pair, 32);
    std::memcpy(reversed + kCensusBytes * (n - 2 - i), &pair, sizeof pair);
  }
  if (i < n) std::memcpy(reversed, census + kCensusBytes * i, kCensusBytes);
}

namespace {
StereoKernels stereo_kernels_ref() {
  return {CensusLayout::planes, census_row_ref,  cost_row_ref,
          sgm_row_ref,          box_columns_ref, bm_row_ref};
}
}  // namespace

StereoKernels stereo_kernels(SimdPath path) {
  static constexpr KernelSet<StereoKernels()> kKernels{stereo_kernels_ref, stereo_kernels_neon,
                                                       EPIPOLE_AVX2_KERNEL(stereo_kernels_avx2)};
  return kKernels.pick(path)();
}

}  // namespace kernels

namespace {
constexpr int kWarmupRows = 24;  // SGM: rows aggregated above a stripe before it is output
std::size_t bytes_of(const auto& v) {
  return v.size() * sizeof(v[0]);
}
}  // namespace

struct StereoMatcher::Worker {
  std::vector<std::uint8_t> left_census, right_census, reversed;  // in the kernels' layout
  std::vector<std::uint8_t> cost;         // SGM: one row; BM: a ring of block_size + 1 rows
  std::vector<std::uint8_t> paths[2][3];  // SGM: previous/current row of the 3 downward paths
  std::vector<std::uint8_t> mins[2][3];
  std::vector<std::uint8_t> scratch;   // SGM: the horizontal paths
  std::vector<std::uint16_t> columns;  // BM: vertical box sums
  std::vector<std::uint16_t> sums;     // the aggregated costs of a row
  std::vector<std::uint16_t> window;   // winner take all: the right image's candidates
  std::vector<std::int16_t> best, right_best;
  kernels::StereoKernels kernels;  // the path's, picked once

  // f(buffer) for every buffer (self: a Worker, const or not).
  static void each_buffer(auto& self, auto&& f) {
    f(self.left_census);
    f(self.right_census);
    f(self.reversed);
    f(self.cost);
    f(self.scratch);
    f(self.columns);
    f(self.sums);
    f(self.window);
    f(self.best);
    f(self.right_best);
    for (int i = 0; i < 2; ++i) {
      for (int k = 0; k < 3; ++k) {
        f(self.paths[i][k]);
        f(self.mins[i][k]);
      }
    }
  }
  std::size_t bytes() const {
    std::size_t n = 0;
    each_buffer(*this, [&](const auto& v) { n += bytes_of(v); });
    return n;
  }
  void cost_row(GrayView left, GrayView right, int y, int disparities, int bits,
                std::uint8_t* cost_out);

  // Every buffer sized for the image and the method, once.
  void allocate(const StereoConfig& config, SimdPath path) {
    const std::size_t uw = static_cast<std::size_t>(config.width);
    const std::size_t ud = static_cast<std::size_t>(config.max_disparity);
    const std::size_t wd = uw * ud;
    const std::size_t stride = ud + 32;
    kernels = kernels::stereo_kernels(path);
    left_census.assign(kernels::kCensusBytes * uw, 0);
    right_census.assign(kernels::kCensusBytes * uw, 0);
    reversed.assign(kernels::kCensusBytes * (uw + ud), 0);
    sums.assign(wd, 0);
    window.assign(2 * (uw + ud), 0);
    best.assign(uw, -1);
    right_best.assign(uw, -1);
    if (config.method != StereoMethod::sgm) {
      cost.assign(wd * static_cast<std::size_t>(config.block_size + 1), 0);
      columns.assign(wd, 0);
      return;
    }
    cost.assign(wd, 0);
    scratch.assign(2 * stride, 0);
    for (auto& row : paths) {
      for (auto& p : row) {
        p.assign((uw + 2) * stride, 0);
        for (std::size_t x = 0; x < uw; ++x) {
          p[(x + 1) * stride + 15] = kernels::kSgmPad;
          p[(x + 1) * stride + 16 + ud] = kernels::kSgmPad;
        }
      }
    }
    for (auto& row : mins) {
      for (auto& m : row) m.assign(uw + 2, 0);
    }
  }
};

namespace {

void check_config(const StereoConfig& config, SimdPath path, const ThreadPool* pool) {
  const int W = config.width;
  const int H = config.height;
  const int D = config.max_disparity;
  require(D >= 16 && D <= 256 && D % 16 == 0, "maximum disparity ", D,
          " must be a multiple of 16 in 16..256");
  require(W >= 16 && H >= 8 && W <= 65535 && H <= 65535, "image size ", W, "x", H,
          " is outside 16x8..65535x65535 for stereo matching");
  require(D < W, "disparity range ", D, " is not smaller than the image width ", W);
  require(config.p1 >= 1 && config.p2 >= config.p1 && config.p2 <= kernels::kMaxSgmP2,
          "SGM penalties P1 ", config.p1, ", P2 ", config.p2,
          " must satisfy 1 <= P1 <= P2 <= ", kernels::kMaxSgmP2);
  require(config.block_size >= 3 && config.block_size <= 21 && config.block_size % 2 == 1,
          "block size ", config.block_size, " must be odd, in 3..21");
  require(config.uniqueness >= 0 && config.uniqueness <= 99, "uniqueness ratio ", config.uniqueness,
          " must be in 0..99 percent");
  require(config.hole_fill >= 0 && config.hole_fill <= W, "hole filling up to ", config.hole_fill,
          " pixels: expected 0 (off) to the image width ", W);
  require(config.spatial_percent >= 0 && config.spatial_percent <= 99, "spatial filter weight ",
          config.spatial_percent, " %: expected 0 (off) to 99");
  require(config.speckle_size >= 0, "speckle size ", config.speckle_size,
          ": expected 0 (off) or more");
  require(config.speckle_range >= 0 && config.speckle_range <= 255, "speckle range ",
          config.speckle_range, " px: expected 0..255");
  require(simd_path_available(path), "kernel path ", to_string(path),
          " is not available on this CPU");
  require(config.threads >= 1 && config.threads <= 64, "stereo threads ", config.threads,
          " is outside 1..64");
  require(pool == nullptr || pool->threads() <= config.threads, "the stereo matcher's pool has ",
          pool == nullptr ? 0 : pool->threads(), " workers, more than its ", config.threads,
          " threads");
}

}  // namespace

StereoMatcher::StereoMatcher(const StereoConfig& config, SimdPath path, ThreadPool* pool)
    : config_(config), path_(path), pool_(pool) {
  check_config(config, path, pool);
  const int W = config.width;
  const int H = config.height;
  if (pool_ == nullptr) {
    own_pool_ = std::make_unique<ThreadPool>(config.threads);
    pool_ = own_pool_.get();
  }
  for (int t = 0; t < config.threads; ++t) {
    auto w = std::make_unique<Worker>();
    w->allocate(config, path);
    workers_.push_back(std::move(w));
  }
  const std::size_t padded = (static_cast<std::size_t>(W) + 2) * (static_cast<std::size_t>(H) + 2);
  padded_.assign(padded, kInvalidDisparity);
  disparity_ = ImageView<std::int16_t>(padded_.data() + W + 3, W, H, W + 2);
  if (config.speckle_size > 0) {
    speckles_ = std::make_unique<SpeckleFilter>(W, H, config.speckle_size, config.speckle_range);
  }
  if (config.confidence) confidence_ = Image<std::uint8_t>(W, H);
  if (config.spatial_percent > 0) {
    spatial_ = std::make_unique<SpatialFilter>(W, H, config.spatial_percent,
                                               config.spatial_max_step, config.spatial_passes);
  }
  if (config.temporal_percent > 0) {
    temporal_ =
        std::make_unique<TemporalFilter>(W, H, config.temporal_percent, config.temporal_max_step);
  }
}

StereoMatcher::~StereoMatcher() = default;

std::size_t StereoMatcher::working_set_bytes() const {
  std::size_t n = bytes_of(padded_);
  if (speckles_) n += speckles_->working_set_bytes();
  for (const auto& w : workers_) n += w->bytes();
  if (spatial_) n += spatial_->working_set_bytes();
  if (temporal_) n += temporal_->working_set_bytes();
  n += confidence_.size_bytes();
  return n;
}

ImageView<const std::int16_t> StereoMatcher::compute(GrayView left, GrayView right) {
  const int stripes = start(left, right);
  pool_->run(stripes, [&](int stripe, int worker) { run_stripe(stripe, worker); });
  return finish();
}

int StereoMatcher::start(GrayView left, GrayView right) {
  require(same_size(left, right), "left image ", left.width(), "x", left.height(),
          " and right image ", right.width(), "x", right.height(), " differ in size");
  require(left.width() == config_.width && left.height() == config_.height, "images are ",
          left.width(), "x", left.height(), " but the matcher is configured for ", config_.width,
          "x", config_.height);
  left_ = left;
  right_ = right;
  return config_.threads;
}

ImageView<const std::int16_t> StereoMatcher::finish() {
  if (speckles_) speckles_->apply(disparity_, path_);
  if (!confidence_.empty()) {
    // What the left-right check refused and the speckles removed have no confidence either;
    // the holes filled next keep none.
    for (int y = 0; y < config_.height; ++y) {
      const std::int16_t* d = disparity_.row(y);
      std::uint8_t* c = confidence_.view().row(y);
      for (int x = 0; x < config_.width; ++x) c[x] = d[x] < 0 ? 0 : c[x];
    }
  }
  if (config_.fill_occlusions) fill_occlusions();
  if (spatial_) spatial_->apply(disparity_, path_);
  fill_holes(disparity_, config_.hole_fill, path_);
  if (temporal_) temporal_->apply(disparity_, path_);
  return disparity_;
}

void StereoMatcher::reset_history() {
  if (temporal_) temporal_->reset();
}

// The census of row y of both images (the right one reversed), then its cost into `cost`: the
// census's first `bits` bits.
void StereoMatcher::Worker::cost_row(GrayView left, GrayView right, int y, int disparities,
                                     int bits, std::uint8_t* cost_out) {
  const int width = left.width();
  const std::uint8_t* rows[7];
  for (const GrayView* image : {&left, &right}) {
    for (int i = 0; i < 7; ++i) {
      rows[i] = image->row(std::clamp(y - kernels::kCensusRadiusY + i, 0, left.height() - 1));
      race_check_read(rows[i], static_cast<std::size_t>(width));  // race_annotations.hpp
    }
    kernels.census(rows, width, bits, image == &left ? left_census.data() : right_census.data());
  }
  kernels::reverse_census(kernels.census_layout, right_census.data(), width, width + disparities,
                          reversed.data());
  kernels.cost(left_census.data(), reversed.data(), width, disparities, bits, cost_out);
}

namespace {

// The left-right check's mark of an occluded pixel (invalid, as every negative value), which
// finish() fills or turns into kInvalidDisparity.
constexpr std::int16_t kOccluded = 2 * kInvalidDisparity;

// The winner take all of a row goes straight into the output row `out`, and its confidence
// into `confidence` (null: none wanted).
kernels::WtaRow wta_row(const StereoConfig& config, StereoMatcher::Worker& w, std::int16_t* out,
                        std::uint8_t* confidence) {
  const auto width = static_cast<std::size_t>(config.width);
  race_check_write(out, width * sizeof(*out));  // race_annotations.hpp
  if (confidence != nullptr) race_check_write(confidence, width);
  return kernels::WtaRow{config.uniqueness, out,       w.best.data(), w.right_best.data(),
                         w.window.data(),   confidence};
}

// The left-right check of an output row: a winner whose right image's winner is too far is
// invalid. With config.fill_occlusions, it is marked kOccluded where that winner is nearer (the
// right camera sees a nearer surface there: this pixel is hidden from it).
void check_row(const StereoConfig& config, const StereoMatcher::Worker& w, std::int16_t* out) {
  if (config.lr_max_diff < 0) return;
  const std::int16_t* best = w.best.data();
  const std::int16_t* right_best = w.right_best.data();
  const std::int16_t refused_nearer = config.fill_occlusions ? kOccluded : kInvalidDisparity;
  for (int x = 0; x < config.width; ++x) {
    const int b = best[x];  // -1: no winner, and out[x] is invalid already
    const int r = right_best[b >= 0 ? x - b : x];
    if (b >= 0 && std::abs(r - b) > config.lr_max_diff) {
      out[x] = r > b ? refused_nearer : kInvalidDisparity;
    }
  }
}

}  // namespace

void StereoMatcher::run_stripe(int stripe, int worker) {
  Worker& w = *workers_[static_cast<std::size_t>(worker)];
  const int stripes = config_.threads;
  const int y0 = stripe * config_.height / stripes;
  const int y1 = (stripe + 1) * config_.height / stripes;
  // With more stripes than rows some have none; SGM's warm-up would still write its winners
  // into row y0, which is the next stripe's.
  if (y0 == y1) return;
  // For ThreadSanitizer, which the stereo kernels are compiled without (race_annotations.hpp):
  // the stripe's kernels write every buffer of its worker. The image rows they read and the
  // output rows they write are told where each row is handed to them (cost_row, wta_row).
  Worker::each_buffer(w, [](auto& v) { race_check_write(v.data(), bytes_of(v)); });
  if (config_.method == StereoMethod::sgm) {
    sgm_stripe(w, y0, y1);
  } else {
    bm_stripe(w, y0, y1);
  }
}

// Rows y0..y1 of the output, aggregated from kWarmupRows above (those belong to the stripe
// above, which writes them itself).
void StereoMatcher::sgm_stripe(Worker& w, int y0, int y1) {
  const int W = config_.width;
  const int D = config_.max_disparity;
  const std::size_t stride = static_cast<std::size_t>(D) + 32;
  int prev = 0;
  for (int dir = 0; dir < 3; ++dir) {
    auto& p = w.paths[prev][dir];
    for (int x = 0; x < W; ++x) {
      std::fill_n(
          p.begin() + static_cast<std::ptrdiff_t>((static_cast<std::size_t>(x) + 1) * stride + 16),
          D, std::uint8_t{0});
    }
    std::fill(w.mins[prev][dir].begin(), w.mins[prev][dir].end(), std::uint8_t{0});
  }
  for (int y = std::max(0, y0 - kWarmupRows); y < y1; ++y) {
    w.cost_row(left_, right_, y, D, kernels::kCensusBits, w.cost.data());
    kernels::SgmRow row{};
    row.cost = w.cost.data();
    row.width = W;
    row.disparities = D;
    row.p1 = config_.p1;
    row.p2 = config_.p2;
    for (int dir = 0; dir < 3; ++dir) {
      row.prev[dir] = w.paths[prev][dir].data();
      row.cur[dir] = w.paths[1 - prev][dir].data();
      row.prev_min[dir] = w.mins[prev][dir].data();
      row.cur_min[dir] = w.mins[1 - prev][dir].data();
    }
    row.scratch = w.scratch.data();
    row.sums = w.sums.data();
    // Warm-up rows write their winners into the row that follows them in the output; it is
    // overwritten before it is final.
    row.wta =
        wta_row(config_, w, disparity_.row(y >= y0 ? y : y0), confidence_row(y >= y0 ? y : y0));
    w.kernels.sgm(row);
    prev = 1 - prev;
    if (y >= y0) check_row(config_, w, disparity_.row(y));
  }
}

// Block matching: a ring of cost rows y - r - 1 .. y + r and their vertical sums, over the
// sparse census (stereo_census.hpp).
void StereoMatcher::bm_stripe(Worker& w, int y0, int y1) {
  const int H = config_.height;
  const int D = config_.max_disparity;
  const std::ptrdiff_t wd = static_cast<std::ptrdiff_t>(config_.width) * D;
  const int r = config_.block_size / 2;
  const int ring = config_.block_size + 1;
  const auto ring_row = [&](int y) { return w.cost.data() + (y % ring) * wd; };
  constexpr int kBits = kernels::kSparseCensusBits;
  std::fill(w.columns.begin(), w.columns.end(), std::uint16_t{0});
  const int first = std::max(0, y0 - r);
  for (int y = first; y < std::min(H, y0 + r); ++y) {
    w.cost_row(left_, right_, y, D, kBits, ring_row(y));
    w.kernels.box_columns(w.columns.data(), ring_row(y), nullptr, static_cast<int>(wd));
  }
  for (int y = y0; y < y1; ++y) {
    kernels::BmRow row{nullptr,
                       nullptr,
                       w.columns.data(),
                       config_.width,
                       D,
                       r,
                       kBits,
                       w.sums.data(),
                       wta_row(config_, w, disparity_.row(y), confidence_row(y))};
    if (y + r < H) {
      w.cost_row(left_, right_, y + r, D, kBits, ring_row(y + r));
      row.entering = ring_row(y + r);
    }
    if (y - r - 1 >= first) row.leaving = ring_row(y - r - 1);
    w.kernels.bm(row);
    check_row(config_, w, disparity_.row(y));
  }
}

// Each run of invalid pixels along a row with a pixel the left-right check found occluded takes
// the disparity of its left neighbour (the background) when the geometry says it is an
// occlusion: a nearer surface on its right, the run as wide as the step to it, and clear of the
// left border. The marks become kInvalidDisparity where nothing is filled.
void StereoMatcher::fill_occlusions() {
  const int W = config_.width;
  for (int y = 0; y < config_.height; ++y) {
    std::int16_t* d = disparity_.row(y);
    for (int x = 0; x < W;) {
      if (d[x] >= 0) {
        ++x;
        continue;
      }
      const int begin = x;
      bool occluded = false;
      for (; x < W && d[x] < 0; ++x) {
        occluded = occluded || d[x] == kOccluded;
        d[x] = kInvalidDisparity;
      }
      if (!occluded || begin == 0 || x == W) continue;
      // An occlusion lies left of a nearer surface and is as wide as the step to it: the
      // background shows there in the left image only.
      const int background = d[begin - 1];
      const int step = (d[x] - background) / kDisparityScale;
      // Near the left border the right image has nothing to show: those runs are mismatches.
      const bool inside = begin >= d[x] / kDisparityScale;
      if (inside && step > 0 && std::abs(x - begin - step) <= std::max(2, step / 4)) {
        std::fill(d + begin, d + x, static_cast<std::int16_t>(background));
      }
    }
  }
}

}  // namespace epipole::vision
