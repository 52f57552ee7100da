#pragma once

// The Viola-Jones detector: a boosted cascade (cascade_model.hpp) run over an image pyramid,
// with the same windows, decisions and grouping as cv::CascadeClassifier::detectMultiScale
// (OpenCV 4.6), so that it finds the same boxes. docs/vision.md, "Viola-Jones cascade".

#include <cstddef>
#include <memory>
#include <span>

#include "epipole/core/image.hpp"
#include "epipole/core/simd.hpp"
#include "epipole/vision/cascade_model.hpp"

namespace epipole::vision {

struct CascadeConfig {
  int max_width = 0;  // the largest image detect() accepts
  int max_height = 0;
  double scale_factor = 1.1;  // > 1: each pyramid level is this much smaller
  // Groups of raw hits with at most this many members are dropped (groupRectangles'
  // groupThreshold, eps 0.2); 0 returns the raw hits ungrouped, as OpenCV does.
  int min_neighbors = 3;
  int min_object_width = 0;  // smaller windows are not searched (0: none)
  int min_object_height = 0;
  int max_object_width = 0;  // larger windows are not searched (0: the image size)
  int max_object_height = 0;
  int max_raw_hits = 5'000;  // bounds: hits beyond them are dropped and truncated() says so
  int max_detections = 1'000;
  // Workers that may search levels at once (search_level's `worker`): each has its own level
  // image and integral planes.
  int workers = 1;
};

struct Detection {
  int x = 0;
  int y = 0;
  int width = 0;
  int height = 0;
  int neighbors = 0;  // raw hits in the group (1 for ungrouped hits)
  friend bool operator==(const Detection&, const Detection&) = default;
};

// Fixed memory: the constructor allocates the evaluation tables, the grouping scratch and, for
// each worker, a pyramid level, the integral images (upright, of squares, and tilted when the
// cascade has tilted features) and a raw hit list; detect() never allocates.
class CascadeDetector {
 public:
  // Throws Error for a bad configuration (sizes, scale factor, bounds).
  CascadeDetector(const CascadeModel& model, const CascadeConfig& config,
                  SimdPath path = best_simd_path());
  ~CascadeDetector();
  CascadeDetector(CascadeDetector&&) noexcept;
  CascadeDetector& operator=(CascadeDetector&&) noexcept;

  // The grouped detections of an 8-bit gray image no larger than the configured size, clipped
  // to the image, in OpenCV's order. The span stays valid until the next call.
  std::span<const Detection> detect(GrayView image);

  // detect() cut into tasks for a thread pool: start() returns the number of pyramid levels
  // (largest first); search_level(i, worker) for each of them, on any workers below
  // config().workers, at once when the workers differ; then finish() gives what detect() would.
  // `image` must stay unchanged until finish().
  int start(GrayView image);
  void search_level(int level, int worker);
  std::span<const Detection> finish();

  // The last image's raw hits (windows that passed every stage), before grouping, in OpenCV's
  // order (level by level, row by row).
  std::span<const Detection> raw_hits() const;
  // True when the last image had more raw hits or detections than the bounds.
  bool truncated() const;
  // Pyramid levels the last image was searched at.
  int levels() const;

  const CascadeConfig& config() const;
  SimdPath simd_path() const;
  // False when the cascade is not stump-based (or its leaves cannot be summed exactly in fixed
  // point): every path then evaluates windows with the reference code.
  bool simd_windows() const;
  // Everything the constructor allocated: evaluation tables (two layouts), pyramid level,
  // integral planes, scratch rows, coefficients, hit lists and grouping scratch.
  std::size_t working_set_bytes() const;

 private:
  struct State;
  std::unique_ptr<State> state_;
};

}  // namespace epipole::vision
