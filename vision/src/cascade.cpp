// The Viola-Jones detector (OpenCV 4.6's CascadeClassifier::detectMultiScale, single image,
// CPU path): the scales, the pyramid (cv::resize INTER_LINEAR_EXACT), the integral images, the
// window scan with its step and skipping, groupRectangles and the final clipping. The reference
// kernels for the integral images and the resize are here; the window kernels are in
// cascade_program.cpp (reference) and cascade_simd.hpp (NEON, AVX2).
#include "epipole/vision/cascade.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>

#include "cascade_kernels.hpp"
#include "cascade_program.hpp"
#include "epipole/core/error.hpp"
#include "epipole/core/race_annotations.hpp"
#include "kernel_set.hpp"

namespace epipole::vision {

namespace kernels {

void integral_row_ref(const std::uint8_t* row, int width, const std::uint32_t* sum_above,
                      const std::uint32_t* square_above, std::uint32_t* sum, std::uint32_t* square,
                      std::uint32_t* prefix) {
  integral_first_entries(sum_above, square_above, sum, square, prefix);
  integral_columns(row, 0, width, sum_above, square_above, sum, square, prefix, 0, 0);
}

void tilted_row_ref(const std::uint32_t* prefix, int width, const std::uint32_t* left_above,
                    const std::uint32_t* right_above, std::uint32_t* left, std::uint32_t* right,
                    std::uint32_t* tilted) {
  right[0] = 0;
  tilted_columns(prefix, 0, width, left_above, right_above, left, right, tilted);
}

void resize_columns_ref(const std::uint8_t* row, int source_width, const std::int32_t* offsets,
                        const std::uint16_t* weights, int width, std::uint16_t* out) {
  for (int x = 0; x < width; ++x) {
    const std::int32_t o = offsets[x];
    unsigned v = row[o] * weights[2 * x];
    if (o + 1 < source_width) v += row[o + 1] * weights[2 * x + 1];
    out[x] = static_cast<std::uint16_t>(v);
  }
}

void resize_rows_ref(const std::uint16_t* top, const std::uint16_t* bottom, std::uint16_t w0,
                     std::uint16_t w1, int width, std::uint8_t* out) {
  for (int x = 0; x < width; ++x) {
    out[x] =
        static_cast<std::uint8_t>((top[x] * unsigned{w0} + bottom[x] * unsigned{w1} + 32768) >> 16);
  }
}

void resize_coefficients(int source, int size, std::int32_t* offsets, std::uint16_t* weights) {
  const double scale = 1.0 / (static_cast<double>(size) / source);
  for (int i = 0; i < size; ++i) {
    const double f = scale * (i + 0.5) - 0.5;
    const double whole = std::floor(f);
    std::uint16_t w1 = 0;
    if (whole < 0 || source == 1) {
      offsets[i] = 0;
    } else if (whole >= source - 1) {
      offsets[i] = source - 1;
    } else {
      offsets[i] = static_cast<std::int32_t>(whole);
      w1 = static_cast<std::uint16_t>(std::lrint((f - whole) * 256.0));
    }
    weights[2 * i] = static_cast<std::uint16_t>(256 - w1);
    weights[2 * i + 1] = w1;
  }
}

IntegralRowKernel* integral_row_kernel(SimdPath path) {
  return KernelSet<IntegralRowKernel>{integral_row_ref, integral_row_neon,
                                      EPIPOLE_AVX2_KERNEL(integral_row_avx2)}
      .pick(path);
}
// No AVX2 version (that path runs the NEON one): it is a few adds a word.
TiltedRowKernel* tilted_row_kernel(SimdPath path) {
  return KernelSet<TiltedRowKernel>{tilted_row_ref, tilted_row_neon, nullptr}.pick(path);
}
ResizeColumnsKernel* resize_columns_kernel(SimdPath path) {
  return KernelSet<ResizeColumnsKernel>{resize_columns_ref, resize_columns_neon,
                                        EPIPOLE_AVX2_KERNEL(resize_columns_avx2)}
      .pick(path);
}
ResizeRowsKernel* resize_rows_kernel(SimdPath path) {
  return KernelSet<ResizeRowsKernel>{resize_rows_ref, resize_rows_neon,
                                     EPIPOLE_AVX2_KERNEL(resize_rows_avx2)}
      .pick(path);
}

}  // namespace kernels

namespace {

// OpenCV's cvRound: to nearest, ties to even.
int round_even(double v) {
  return static_cast<int>(std::lrint(v));
}
int round_even(float v) {
  return static_cast<int>(std::lrint(v));
}

// SIMD kernels may read up to this many columns past a level's last window (masked lanes).
constexpr int kRowSlack = 64;

CascadeConfig checked(const CascadeConfig& c) {
  // (At most 16384 keeps every offset into the three integral planes within int32.)
  require(c.max_width >= 1 && c.max_height >= 1 && c.max_width <= 16384 && c.max_height <= 16384,
          "cascade detector size ", c.max_width, "x", c.max_height, " (1 to 16384 allowed)");
  require(std::isfinite(c.scale_factor) && c.scale_factor > 1.0 && c.scale_factor <= 100.0,
          "cascade scale factor ", c.scale_factor, " must be above 1");
  require(c.min_neighbors >= 0, "cascade min_neighbors ", c.min_neighbors, " is negative");
  require(c.min_object_width >= 0 && c.min_object_height >= 0 && c.max_object_width >= 0 &&
              c.max_object_height >= 0,
          "cascade object sizes must not be negative");
  require(c.max_raw_hits >= 1 && c.max_detections >= 1, "cascade bounds max_raw_hits ",
          c.max_raw_hits, " and max_detections ", c.max_detections, " must be positive");
  require(c.workers >= 1 && c.workers <= 64, "cascade workers ", c.workers, " (1 to 64 allowed)");
  return c;
}

}  // namespace

// What one worker needs to search a pyramid level: the level image, its integral planes and
// their scratch rows, the resize coefficients, and the raw hits of the levels it searched.
struct CascadeWorker {
  CascadeWorker(const CascadeConfig& c, std::ptrdiff_t row_stride, std::ptrdiff_t plane_entries,
                int plane_count, bool has_tilted)
      : level(c.max_width, c.max_height),
        width(static_cast<std::size_t>(c.max_width)),
        height(static_cast<std::size_t>(c.max_height)),
        stride(static_cast<std::size_t>(row_stride)),
        plane_size(static_cast<std::size_t>(plane_count) * static_cast<std::size_t>(plane_entries)),
        tilted(has_tilted),
        hit_capacity(static_cast<std::size_t>(c.max_raw_hits)) {
    planes = std::make_unique<std::uint32_t[]>(plane_size);
    if (tilted) {
      prefix = std::make_unique<std::uint32_t[]>(width + 2);
      for (auto& r : tilted_rows) r = std::make_unique<std::uint32_t[]>(width + 2);
    }
    // Split levels: two rows of sums and squares (by row parity), and one tilted row.
    for (auto& r : scratch) r = std::make_unique<std::uint32_t[]>(2 * stride);
    column_offsets = std::make_unique<std::int32_t[]>(width);
    column_weights = std::make_unique<std::uint16_t[]>(2 * width);
    row_offsets = std::make_unique<std::int32_t[]>(height);
    row_weights = std::make_unique<std::uint16_t[]>(2 * height);
    for (auto& r : resized_rows) r = std::make_unique<std::uint16_t[]>(width);
    row_hits = std::make_unique<std::int32_t[]>(width + 1);
    hits = std::make_unique<Detection[]>(hit_capacity);
  }

  // Every buffer, as f(data, bytes): what bytes() counts, and what a level's search tells
  // ThreadSanitizer it writes (the kernels it calls are not instrumented: race_annotations.hpp).
  template <typename Self, typename F>
  static void each_buffer(Self& self, F&& f) {
    const std::size_t w = self.width;
    const std::size_t h = self.height;
    f(self.level.view().data(), self.level.size_bytes());
    f(self.planes.get(), self.plane_size * 4);
    if (self.tilted) {
      f(self.prefix.get(), (w + 2) * 4);
      for (auto& r : self.tilted_rows) f(r.get(), (w + 2) * 4);
    }
    for (auto& r : self.scratch) f(r.get(), 2 * self.stride * 4);
    f(self.column_offsets.get(), w * 4);
    f(self.column_weights.get(), 2 * w * 2);
    f(self.row_offsets.get(), h * 4);
    f(self.row_weights.get(), 2 * h * 2);
    for (auto& r : self.resized_rows) f(r.get(), w * 2);
    f(self.row_hits.get(), (w + 1) * 4);
    f(self.hits.get(), self.hit_capacity * sizeof(Detection));
  }

  std::size_t bytes() const {
    std::size_t total = 0;
    each_buffer(*this, [&](const void*, std::size_t n) { total += n; });
    return total;
  }

  GrayImage level;
  std::size_t width;   // the largest level's
  std::size_t height;  // the largest level's
  std::size_t stride;  // of a plane row
  std::size_t plane_size;
  bool tilted;
  std::size_t hit_capacity;
  std::unique_ptr<std::uint32_t[]> planes;
  std::unique_ptr<std::uint32_t[]> prefix;
  std::unique_ptr<std::uint32_t[]> tilted_rows[4];
  std::unique_ptr<std::uint32_t[]> scratch[3];
  std::unique_ptr<std::int32_t[]> column_offsets;
  std::unique_ptr<std::uint16_t[]> column_weights;
  std::unique_ptr<std::int32_t[]> row_offsets;
  std::unique_ptr<std::uint16_t[]> row_weights;
  std::unique_ptr<std::uint16_t[]> resized_rows[2];
  std::unique_ptr<std::int32_t[]> row_hits;
  std::unique_ptr<Detection[]> hits;  // the raw hits of this image's levels searched here
  int hit_count = 0;
  bool truncated = false;  // a hit did not fit in `hits`
};

struct CascadeDetector::State {
  State(const CascadeModel& model, const CascadeConfig& c, SimdPath p)
      : config(checked(c)),
        path(p),
        stride((c.max_width + 1 + kRowSlack + 15) / 16 * 16),
        plane((static_cast<std::ptrdiff_t>(c.max_height) + 2) * stride),
        programs{kernels::CascadeProgram(model, {stride, 0}, plane, 2 * plane),
                 kernels::CascadeProgram(model, {stride / 2, plane / 2}, plane, 2 * plane)},
        tilted(model.has_tilted_features()),
        squares(model.feature_type() == CascadeFeatureType::haar) {
    windows = kernels::cascade_row_ref;
    if (programs[0].fixed_point_exact && path != SimdPath::reference) {
      static constexpr KernelSet<kernels::CascadeRowKernel> kKernels{
          kernels::cascade_row_ref, kernels::cascade_row_neon,
          EPIPOLE_AVX2_KERNEL(kernels::cascade_row_avx2)};
      windows = kKernels.pick(path);
    }
    integral_row = kernels::integral_row_kernel(path);
    tilted_row = kernels::tilted_row_kernel(path);
    resize_columns = kernels::resize_columns_kernel(path);
    resize_rows = kernels::resize_rows_kernel(path);
    split_row =
        KernelSet<kernels::SplitRowKernel>{kernels::split_row_ref, kernels::split_row_neon, nullptr}
            .pick(path);

    for (int i = 0; i < config.workers; ++i) {
      workers.push_back(
          std::make_unique<CascadeWorker>(config, stride, plane, plane_count(), tilted));
    }
    // The scales of the largest image: smaller images and object limits only drop some.
    for (double factor = 1;; factor *= c.scale_factor) {
      if (round_even(model.window_width() * factor) > c.max_width ||
          round_even(model.window_height() * factor) > c.max_height) {
        break;
      }
      ++max_levels;
    }
    const auto levels = static_cast<std::size_t>(std::max(max_levels, 1));
    scales = std::make_unique<float[]>(levels);
    level_hits = std::make_unique<LevelHits[]>(levels);
    const auto hits = static_cast<std::size_t>(c.max_raw_hits);
    raw = std::make_unique<Detection[]>(hits);
    parent = std::make_unique<int[]>(hits);
    rank = std::make_unique<int[]>(hits);
    label = std::make_unique<int[]>(hits);
    classes = std::make_unique<Detection[]>(hits);
    output = std::make_unique<Detection[]>(static_cast<std::size_t>(c.max_detections));
  }

  std::size_t working_set_bytes() const {
    const auto hits = static_cast<std::size_t>(config.max_raw_hits);
    return programs[0].bytes() + programs[1].bytes() + workers.size() * workers.front()->bytes() +
           static_cast<std::size_t>(max_levels) * (4 + sizeof(LevelHits)) +
           hits * (2 * sizeof(Detection) + 3 * 4) +
           static_cast<std::size_t>(config.max_detections) * sizeof(Detection);
  }

  // Sums, then squares (Haar), then tilted sums (when the cascade has tilted features).
  int plane_count() const { return tilted ? 3 : squares ? 2 : 1; }
  int plan(GrayView image);
  void search_level(int index, CascadeWorker& w);
  void resize_level(CascadeWorker& w, int width, int height);
  void integrate(CascadeWorker& w, GrayView level, bool split);
  void gather_hits();
  void group(int image_width, int image_height);
  int cluster();
  void emit(Detection d, int image_width, int image_height);

  CascadeConfig config;
  SimdPath path;
  std::ptrdiff_t stride;
  std::ptrdiff_t plane;
  kernels::CascadeProgram programs[2];  // levels searched at step 1, and at step 2 (split)
  bool tilted;
  bool squares;  // Haar: the variance normalisation needs the squares' plane
  kernels::CascadeRowKernel* windows = nullptr;
  kernels::IntegralRowKernel* integral_row = nullptr;
  kernels::TiltedRowKernel* tilted_row = nullptr;
  kernels::ResizeColumnsKernel* resize_columns = nullptr;
  kernels::ResizeRowsKernel* resize_rows = nullptr;
  kernels::SplitRowKernel* split_row = nullptr;

  std::vector<std::unique_ptr<CascadeWorker>> workers;
  int max_levels = 0;
  std::unique_ptr<float[]> scales;
  // Where each level of this image left its hits: which worker searched it, and the range.
  struct LevelHits {
    int worker = 0;
    int begin = 0;
    int end = 0;
  };
  std::unique_ptr<LevelHits[]> level_hits;
  GrayView image;  // the image of the search in progress (start() .. finish())
  int stripes = 0;
  std::unique_ptr<Detection[]> raw;
  std::unique_ptr<int[]> parent;
  std::unique_ptr<int[]> rank;
  std::unique_ptr<int[]> label;
  std::unique_ptr<Detection[]> classes;
  std::unique_ptr<Detection[]> output;
  int raw_count = 0;
  int output_count = 0;
  int level_count = 0;
  bool truncated = false;
};

// cv::resize(image, level, size, INTER_LINEAR_EXACT): each destination row from two source rows'
// horizontal passes (cached: consecutive rows share one).
void CascadeDetector::State::resize_level(CascadeWorker& w, int width, int height) {
  kernels::resize_coefficients(image.width(), width, w.column_offsets.get(),
                               w.column_weights.get());
  kernels::resize_coefficients(image.height(), height, w.row_offsets.get(), w.row_weights.get());
  int cached[2] = {-1, -1};
  const int last = image.height() - 1;
  for (int y = 0; y < height; ++y) {
    const int rows[2] = {w.row_offsets[y], std::min(w.row_offsets[y] + 1, last)};
    const std::uint16_t* pass[2] = {nullptr, nullptr};
    for (int k = 0; k < 2; ++k) {
      int slot = cached[0] == rows[k] ? 0 : cached[1] == rows[k] ? 1 : -1;
      if (slot < 0) {
        // A slot the other row does not need.
        if (k == 0) {
          slot = cached[0] == rows[1] ? 1 : 0;
        } else {
          slot = pass[0] == w.resized_rows[0].get() ? 1 : 0;
        }
        resize_columns(image.row(rows[k]), image.width(), w.column_offsets.get(),
                       w.column_weights.get(), width, w.resized_rows[slot].get());
        cached[slot] = rows[k];
      }
      pass[k] = w.resized_rows[slot].get();
    }
    resize_rows(pass[0], pass[1], w.row_weights[2 * y], w.row_weights[2 * y + 1], width,
                w.level.view().row(y));
  }
}

// The integral images of one level into the worker's planes: row 0 is zero, row Y + 1 holds the
// sums over image rows 0..Y. With `split`, rows are computed in the scratch rows and stored with
// their even and odd columns apart (programs[1]'s layout).
void CascadeDetector::State::integrate(CascadeWorker& w, GrayView level, bool split) {
  const int width = level.width();
  const int entries = width + 1;
  const std::ptrdiff_t row_stride = split ? stride / 2 : stride;
  std::uint32_t* sum = w.planes.get();
  std::uint32_t* square = squares ? sum + plane : nullptr;
  std::uint32_t* tilted_plane = tilted ? sum + 2 * plane : nullptr;
  const auto clear = [](std::uint32_t* row, std::size_t n) { std::memset(row, 0, n * 4); };
  for (std::uint32_t* p : {sum, square, tilted_plane}) {
    if (p == nullptr) continue;
    clear(p, static_cast<std::size_t>(entries));
    if (split) clear(p + plane / 2, static_cast<std::size_t>(entries));
  }
  if (tilted) {
    for (int k = 0; k < 2; ++k) clear(w.tilted_rows[k].get(), static_cast<std::size_t>(width) + 2);
  }
  if (split) {
    for (int k = 0; k < 2; ++k) clear(w.scratch[k].get(), static_cast<std::size_t>(entries));
  }
  for (int y = 0; y < level.height(); ++y) {
    const std::ptrdiff_t above = y * row_stride;
    const std::ptrdiff_t here = above + row_stride;
    std::uint32_t* prefix_row = tilted ? w.prefix.get() : nullptr;
    if (split) {
      // Scratch rows: sums at 0 / 1 and squares at 2 / 3 by row parity; the tilted row at 4.
      std::uint32_t* sums_above = w.scratch[y & 1].get();
      std::uint32_t* sums = w.scratch[1 - (y & 1)].get();
      std::uint32_t* squares_above = squares ? sums_above + stride : nullptr;
      std::uint32_t* square_row = squares ? sums + stride : nullptr;
      integral_row(level.row(y), width, sums_above, squares_above, sums, square_row, prefix_row);
      split_row(sums, entries, sum + here, sum + plane / 2 + here);
      if (squares) split_row(square_row, entries, square + here, square + plane / 2 + here);
    } else {
      integral_row(level.row(y), width, sum + above, squares ? square + above : nullptr, sum + here,
                   squares ? square + here : nullptr, prefix_row);
    }
    if (tilted) {
      const int from = (y & 1) * 2;
      const int to = 2 - from;
      std::uint32_t* out = split ? w.scratch[2].get() : tilted_plane + here;
      tilted_row(w.prefix.get(), width, w.tilted_rows[from].get(), w.tilted_rows[from + 1].get(),
                 w.tilted_rows[to].get(), w.tilted_rows[to + 1].get(), out);
      if (split) split_row(out, entries, tilted_plane + here, tilted_plane + plane / 2 + here);
    }
  }
}

// The scales of `image`: factor 1, scale_factor, scale_factor^2, ... (in double, as OpenCV)
// while the window fits the image and the maximum size; those below the minimum size are
// skipped. Returns how many levels there are to search.
int CascadeDetector::State::plan(GrayView searched) {
  image = searched;
  const int window_width = programs[0].window_width;
  const int window_height = programs[0].window_height;
  int max_w = config.max_object_width;
  int max_h = config.max_object_height;
  if (max_w == 0 || max_h == 0) max_w = image.width(), max_h = image.height();
  int count = 0;
  for (double factor = 1;; factor *= config.scale_factor) {
    const int w = round_even(window_width * factor);
    const int h = round_even(window_height * factor);
    if (w > max_w || h > max_h || w > image.width() || h > image.height()) break;
    if (w < config.min_object_width || h < config.min_object_height) continue;
    if (count == max_levels) break;  // cannot happen: max_levels is the largest image's count
    scales[count++] = static_cast<float>(factor);
  }
  level_count = count;
  // OpenCV's stripes: their number comes from the first level's width, and their height
  // (rounded to the step) can leave the last rows of a level unsearched.
  stripes = 0;
  if (count > 0) {
    const int first_w =
        std::max(round_even(static_cast<float>(image.width()) / scales[0]) + 1 - window_width, 0);
    stripes = static_cast<int>(std::ceil(first_w / 32.0));
  }
  for (auto& w : workers) {
    w->hit_count = 0;
    w->truncated = false;
  }
  return count;
}

// One pyramid level, searched by worker `w`; its raw hits go to the worker's list.
void CascadeDetector::State::search_level(int index, CascadeWorker& w) {
  const int window_width = programs[0].window_width;
  const int window_height = programs[0].window_height;
  const float scale = scales[index];
  LevelHits& where = level_hits[index];
  where.begin = where.end = w.hit_count;
  if (stripes <= 0) return;
  const int width = round_even(static_cast<float>(image.width()) / scale);
  const int height = round_even(static_cast<float>(image.height()) / scale);
  const int step = scale >= 2 ? 1 : 2;
  const int work_w = std::max(width + 1 - window_width, 0);
  const int work_h = std::max(height + 1 - window_height, 0);
  const int stripe = std::max((work_h / step + stripes - 1) / stripes, 1) * step;
  const int rows_end = std::min(stripes * stripe, work_h);
  const int hit_width = round_even(static_cast<float>(window_width) * scale);
  const int hit_height = round_even(static_cast<float>(window_height) * scale);

  // The kernels below are not instrumented under ThreadSanitizer (vision/CMakeLists.txt): what
  // they read of the shared image and may write of this worker's buffers, told to it here.
  race_check_read(image.data(), static_cast<std::size_t>(image.height() - 1) *
                                        static_cast<std::size_t>(image.stride()) +
                                    static_cast<std::size_t>(image.width()));
  CascadeWorker::each_buffer(w,
                             [](void* data, std::size_t bytes) { race_check_write(data, bytes); });
  GrayView level_view = image;
  if (width != image.width() || height != image.height()) {
    resize_level(w, width, height);
    level_view = GrayView(w.level.view().data(), width, height, w.level.stride());
  }
  const kernels::CascadeProgram& program = programs[step == 2 ? 1 : 0];
  integrate(w, level_view, program.layout.split());
  const int positions = (work_w + step - 1) / step;
  for (int y = 0; y < rows_end; y += step) {
    const int hits = windows(program, w.planes.get() + y * program.layout.row_stride, positions,
                             w.row_hits.get());
    for (int k = 0; k < hits; ++k) {
      if (w.hit_count == config.max_raw_hits) {
        w.truncated = true;
        break;
      }
      w.hits[w.hit_count++] = {round_even(static_cast<float>(w.row_hits[k]) * scale),
                               round_even(static_cast<float>(y) * scale), hit_width, hit_height, 1};
    }
  }
  where.end = w.hit_count;
}

// The levels' hits in level order (OpenCV's), at most max_raw_hits of them. A worker whose own
// list overflowed had more than max_raw_hits hits in all, so the list kept is the same.
void CascadeDetector::State::gather_hits() {
  raw_count = 0;
  truncated = false;
  for (const auto& w : workers) truncated = truncated || w->truncated;
  for (int i = 0; i < level_count; ++i) {
    const LevelHits& where = level_hits[i];
    const Detection* hits = workers[static_cast<std::size_t>(where.worker)]->hits.get();
    const int n = where.end - where.begin;
    const int kept = std::min(n, config.max_raw_hits - raw_count);
    std::copy_n(hits + where.begin, kept, raw.get() + raw_count);
    raw_count += kept;
    truncated = truncated || kept < n;
  }
}

namespace {
constexpr double kGroupEps = 0.2;  // groupRectangles' eps
}  // namespace

// A grouped detection clipped to the image (clipObjects); dropped when nothing of it is left,
// or when the output is full (then `truncated`).
void CascadeDetector::State::emit(Detection d, int image_width, int image_height) {
  const int x0 = std::max(d.x, 0);
  const int y0 = std::max(d.y, 0);
  const int x1 = std::min(d.x + d.width, image_width);
  const int y1 = std::min(d.y + d.height, image_height);
  if (x1 <= x0 || y1 <= y0) return;
  if (output_count == config.max_detections) {
    truncated = true;
    return;
  }
  output[output_count++] = {x0, y0, x1 - x0, y1 - y0, d.neighbors};
}

// The classes of similar raw hits (the transitive closure of SimilarRects, by union-find),
// numbered in order of first appearance, each its hits' average: into `classes`. Returns how
// many there are.
int CascadeDetector::State::cluster() {
  const int n = raw_count;
  const auto similar = [](const Detection& a, const Detection& b) {
    const double delta =
        kGroupEps * (std::min(a.width, b.width) + std::min(a.height, b.height)) * 0.5;
    return std::abs(a.x - b.x) <= delta && std::abs(a.y - b.y) <= delta &&
           std::abs(a.x + a.width - b.x - b.width) <= delta &&
           std::abs(a.y + a.height - b.y - b.height) <= delta;
  };
  const auto root = [this](int i) {
    while (parent[i] != i) i = parent[i] = parent[parent[i]];
    return i;
  };
  for (int i = 0; i < n; ++i) parent[i] = i, rank[i] = 0, label[i] = -1;
  for (int i = 0; i < n; ++i) {
    for (int j = i + 1; j < n; ++j) {
      if (!similar(raw[i], raw[j])) continue;
      int a = root(i);
      int b = root(j);
      if (a == b) continue;
      if (rank[a] < rank[b]) std::swap(a, b);
      parent[b] = a;
      rank[a] += rank[a] == rank[b] ? 1 : 0;
    }
  }
  int class_count = 0;
  for (int i = 0; i < n; ++i) {
    const int r = root(i);
    if (label[r] < 0) {
      label[r] = class_count;
      classes[class_count++] = {0, 0, 0, 0, 0};
    }
    Detection& c = classes[label[r]];
    c.x += raw[i].x;
    c.y += raw[i].y;
    c.width += raw[i].width;
    c.height += raw[i].height;
    ++c.neighbors;
  }
  for (int i = 0; i < class_count; ++i) {
    Detection& c = classes[i];
    const float s = 1.0f / static_cast<float>(c.neighbors);
    c = {round_even(static_cast<float>(c.x) * s), round_even(static_cast<float>(c.y) * s),
         round_even(static_cast<float>(c.width) * s), round_even(static_cast<float>(c.height) * s),
         c.neighbors};
  }
  return class_count;
}

// cv::groupRectangles(hits, min_neighbors, 0.2), then clipObjects: the classes of similar
// rectangles with more than min_neighbors hits; small ones inside bigger, stronger ones
// dropped; clipped to the image.
void CascadeDetector::State::group(int image_width, int image_height) {
  output_count = 0;
  const int threshold = config.min_neighbors;
  if (threshold <= 0 || raw_count == 0) {
    for (int i = 0; i < raw_count; ++i) emit(raw[i], image_width, image_height);
    return;
  }
  const int class_count = cluster();
  for (int i = 0; i < class_count; ++i) {
    const Detection& r1 = classes[i];
    const int n1 = r1.neighbors;
    if (n1 <= threshold) continue;
    bool inside = false;
    for (int j = 0; j < class_count && !inside; ++j) {
      const Detection& r2 = classes[j];
      const int n2 = r2.neighbors;
      if (j == i || n2 <= threshold) continue;
      const int dx = round_even(r2.width * kGroupEps);
      const int dy = round_even(r2.height * kGroupEps);
      inside = r1.x >= r2.x - dx && r1.y >= r2.y - dy && r1.x + r1.width <= r2.x + r2.width + dx &&
               r1.y + r1.height <= r2.y + r2.height + dy && (n2 > std::max(3, n1) || n1 < 3);
    }
    if (!inside) emit(r1, image_width, image_height);
  }
}

CascadeDetector::CascadeDetector(const CascadeModel& model, const CascadeConfig& config,
                                 SimdPath path)
    : state_(std::make_unique<State>(model, config, path)) {}

CascadeDetector::~CascadeDetector() = default;
CascadeDetector::CascadeDetector(CascadeDetector&&) noexcept = default;
CascadeDetector& CascadeDetector::operator=(CascadeDetector&&) noexcept = default;

std::span<const Detection> CascadeDetector::detect(GrayView image) {
  const int levels = start(image);
  for (int i = 0; i < levels; ++i) search_level(i, 0);
  return finish();
}

int CascadeDetector::start(GrayView image) {
  State& s = *state_;
  require(image.width() <= s.config.max_width && image.height() <= s.config.max_height,
          "cascade detector configured for images up to ", s.config.max_width, "x",
          s.config.max_height, " was given a ", image.width(), "x", image.height(), " image");
  s.raw_count = 0;
  s.output_count = 0;
  s.level_count = 0;
  s.truncated = false;
  if (image.empty()) {
    s.image = image;
    return 0;
  }
  return s.plan(image);
}

void CascadeDetector::search_level(int level, int worker) {
  State& s = *state_;
  require(level >= 0 && level < s.level_count && worker >= 0 && worker < s.config.workers,
          "cascade level ", level, " of ", s.level_count, " on worker ", worker, " of ",
          s.config.workers);
  s.level_hits[level].worker = worker;
  s.search_level(level, *s.workers[static_cast<std::size_t>(worker)]);
}

std::span<const Detection> CascadeDetector::finish() {
  State& s = *state_;
  if (s.image.empty()) return {};
  s.gather_hits();
  s.group(s.image.width(), s.image.height());
  return {s.output.get(), static_cast<std::size_t>(s.output_count)};
}

std::span<const Detection> CascadeDetector::raw_hits() const {
  return {state_->raw.get(), static_cast<std::size_t>(state_->raw_count)};
}
bool CascadeDetector::truncated() const {
  return state_->truncated;
}
int CascadeDetector::levels() const {
  return state_->level_count;
}
const CascadeConfig& CascadeDetector::config() const {
  return state_->config;
}
SimdPath CascadeDetector::simd_path() const {
  return state_->path;
}
bool CascadeDetector::simd_windows() const {
  return state_->windows != kernels::cascade_row_ref;
}
std::size_t CascadeDetector::working_set_bytes() const {
  return state_->working_set_bytes();
}

}  // namespace epipole::vision
