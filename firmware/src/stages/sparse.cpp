// Sparse matching: the corners' descriptors matched along the rows (once the corners are
// there), their 3-D points with a calibration (the most distinctive first), and how well the
// rectification holds (the matches' vertical offsets).
#include <algorithm>
#include <vector>

#include "epipole/calib/health.hpp"
#include "epipole/firmware/sparse_points.hpp"
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
  return c;
}

class SparseStage final : public PipelineStage {
 public:
  explicit SparseStage(const StageContext& c)
      : matcher_(sparse_config(c.board), c.path),
        triangulator_(c.triangulator),
        points_(static_cast<std::size_t>(c.board.sparse.max_matches)),
        order_(points_.size()),
        rectified_matches_(points_.size()),
        health_(c.board.sparse.max_matches),
        max_points_(c.board.sparse.max_points) {}

  std::size_t working_set_bytes() const override {
    return matcher_.working_set_bytes() + points_.capacity() * sizeof(SparsePoint) +
           order_.capacity() * sizeof(std::uint32_t) +
           rectified_matches_.capacity() * sizeof(calib::RectifiedMatch) +
           health_.working_set_bytes();
  }
  int add_tasks(PairWork& work) override {
    work_ = &work;
    return work.batch.add(1, task_, work.parts[static_cast<std::size_t>(protocol::Stage::corners)]);
  }

 private:
  void match(const PairWork& work) {
    FrameResult& r = work.result;
    r.matches = matcher_.match(r.left, r.corners_left, r.right, r.corners_right);
    if (triangulator_ != nullptr) triangulate(r);
    if (protocol::has_stage(work.run, protocol::Stage::rectify)) {
      for (std::size_t i = 0; i < r.matches.size(); ++i) {
        const vision::SparseMatch& m = r.matches[i];
        rectified_matches_[i] = {m.xl, m.yl, m.xr, m.yr};
      }
      r.calibration_health = health_.measure({rectified_matches_.data(), r.matches.size()});
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
  int max_points_;
  const PairWork* work_ = nullptr;
  Task task_{*this};
};

}  // namespace

extern constinit const StageDefinition sparse_stage{make_stage<SparseStage>};

}  // namespace epipole::firmware::stages
