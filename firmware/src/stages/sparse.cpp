// Sparse matching: the corners' descriptors matched along the rows (once the corners are
// there), their 3-D points with a calibration (the most distinctive first), and how well the
// rectification holds (the corners matched on a band of rows, their offsets to a fraction of a
// pixel, the right camera's turn over a window of pairs).
#include <algorithm>
#include <vector>

#include "epipole/calib/drift_estimator.hpp"
#include "epipole/calib/health.hpp"
#include "epipole/firmware/rig_correction.hpp"
#include "epipole/firmware/sparse_points.hpp"
#include "epipole/vision/patch_alignment.hpp"
#include "epipole/vision/sparse_stereo.hpp"
#include "stage_files.hpp"

namespace epipole::firmware::stages {

namespace {

vision::SparseStereoConfig sparse_config(const BoardConfig& board) {
  vision::SparseStereoConfig c;
  c.width = board.width();
  c.height = board.height();
  c.max_disparity = board.stereo.max_disparity;
  c.row_tolerance = board.sparse.row_tolerance;
  c.ratio = board.sparse.ratio;
  c.max_distance = board.sparse.max_distance;
  c.max_corners = board.corners.max_corners;
  c.max_matches = board.sparse.max_matches;
  c.band_rows = board.calibration_health.band_rows;
  return c;
}

calib::DriftEstimatorConfig drift_config(const BoardConfig& board) {
  calib::DriftEstimatorConfig c;
  c.max_matches = board.sparse.max_matches;
  c.window_pairs = board.calibration_health.window_pairs;
  return c;
}

class SparseStage final : public PipelineStage {
 public:
  // A pair's matches whose rows are measured: the median's error is well below the patches'
  // noise, and the drift estimator keeps as many a pair.
  static constexpr std::size_t kRowsMeasured = 256;

  explicit SparseStage(const StageContext& c)
      : matcher_(sparse_config(c.board), c.path),
        triangulator_(c.triangulator),
        points_(static_cast<std::size_t>(c.board.sparse.max_matches)),
        order_(points_.size()),
        rectified_matches_(points_.size()),
        health_(c.board.sparse.max_matches),
        correction_(c.correction),
        max_points_(c.board.sparse.max_points) {
    if (c.calibration) drift_.emplace(*c.calibration, drift_config(c.board));
  }

  std::size_t working_set_bytes() const override {
    return matcher_.working_set_bytes() + points_.capacity() * sizeof(SparsePoint) +
           order_.capacity() * sizeof(std::uint32_t) +
           rectified_matches_.capacity() * sizeof(calib::RectifiedMatch) +
           health_.working_set_bytes() + (drift_ ? drift_->working_set_bytes() : 0);
  }
  int add_tasks(PairWork& work) override {
    work_ = &work;
    return work.batch.add(1, task_, work.parts[static_cast<std::size_t>(protocol::Stage::corners)]);
  }

 private:
  void match(const PairWork& work) {
    FrameResult& r = work.result;
    r.matches = matcher_.match(r.left, r.corners_left, r.right, r.corners_right);
    r.left_features = matcher_.left_features();
    if (triangulator_ != nullptr) triangulate(r);
    if (protocol::has_stage(work.run, protocol::Stage::rectify)) measure_rows(r);
  }
  // The corners matched again on a band of rows, each match's offset measured to a fraction of
  // a pixel (a drifted rig's rows are apart; whole-pixel corners cannot show less than one): at
  // most kRowsMeasured of them, evenly over the matches (in row order: over the image).
  void measure_rows(FrameResult& r) {
    // The maps were corrected: the window's matches were measured through the old ones.
    if (drift_ && correction_ != nullptr && correction_->generation() != generation_) {
      generation_ = correction_->generation();
      drift_->set_rig(correction_->rig());
    }
    const std::span<const vision::SparseMatch> band = matcher_.match_band(r.left, r.right);
    const std::size_t step = (band.size() + kRowsMeasured - 1) / kRowsMeasured;
    std::size_t n = 0;
    for (std::size_t i = 0; i < band.size(); i += step) {
      const vision::SparseMatch& m = band[i];
      const vision::PatchOffset o = vision::align_patch(
          r.left, static_cast<int>(m.xl), static_cast<int>(m.yl), r.right, m.xr, m.yr);
      if (o.found) rectified_matches_[n++] = {m.xl, m.yl, m.xl + o.dx, m.yl + o.dy};
    }
    const std::span<const calib::RectifiedMatch> measured{rectified_matches_.data(), n};
    r.calibration_health = health_.measure(measured);
    if (drift_) {
      drift_->add_pair(measured);
      r.drift = drift_->estimate();
    }
  }
  // The matches' points; the most distinctive (smallest descriptor distance) become those sent.
  void triangulate(FrameResult& r) {
    const std::size_t n = triangulate_matches(*triangulator_, r.matches, points_);
    r.points = {points_.data(), n};
    for (std::size_t i = 0; i < n; ++i) order_[i] = static_cast<std::uint32_t>(i);
    const std::size_t keep = std::min(n, static_cast<std::size_t>(max_points_));
    const auto distance = [&](std::uint32_t i) { return points_[i].distance; };
    std::partial_sort(order_.begin(), order_.begin() + static_cast<std::ptrdiff_t>(keep),
                      order_.begin() + static_cast<std::ptrdiff_t>(n),
                      [&](std::uint32_t a, std::uint32_t b) {
                        return distance(a) != distance(b) ? distance(a) < distance(b) : a < b;
                      });
    r.best_points = {order_.data(), keep};
  }

  struct Task {
    SparseStage& s;
    void operator()(int, int) const { s.match(*s.work_); }
  };

  vision::SparseStereoMatcher matcher_;
  const calib::Triangulator* triangulator_;
  std::vector<SparsePoint> points_;
  std::vector<std::uint32_t> order_;
  std::vector<calib::RectifiedMatch> rectified_matches_;
  calib::CalibrationHealth health_;
  std::optional<calib::DriftEstimator> drift_;  // with a calibration
  const RigCorrection* correction_;
  std::uint32_t generation_ = 0;  // of the rig the window was measured through
  int max_points_;
  const PairWork* work_ = nullptr;
  Task task_{*this};
};

}  // namespace

extern constinit const StageDefinition sparse_stage{make_stage<SparseStage>};

}  // namespace epipole::firmware::stages
