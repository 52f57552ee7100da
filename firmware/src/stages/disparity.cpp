// The dense disparity: the matcher's row stripes on the pool; the stripe that ends last ends it
// (speckles, the depth's outputs: the depth grid, and the obstacle sectors unless the ground stage
// runs on the pair and measures them above the ground), so no worker waits.
#include <atomic>

#include "epipole/vision/stereo.hpp"
#include "stage_files.hpp"

namespace epipole::firmware::stages {

namespace {

vision::StereoConfig stereo_config(const StageContext& c) {
  vision::StereoConfig stereo = c.board.stereo;
  stereo.width = c.board.width();
  stereo.height = c.board.height();
  // The matcher's confidence, when the depth's outputs filter by it.
  const BoardConfig::DepthGrid& grid = c.board.depth_grid;
  stereo.confidence = c.calibration && (c.board.obstacles.min_confidence > 0 ||
                                        (grid.columns > 0 && grid.min_confidence > 0));
  // One pool for every stage: threads.count workers, one per CPU, the disparity in as many
  // stripes.
  stereo.threads = c.board.threads.count;
  return stereo;
}

class DisparityStage final : public PipelineStage {
 public:
  explicit DisparityStage(const StageContext& c)
      : matcher_(stereo_config(c), c.path, &c.pool), obstacles_(c.obstacles), grid_(c.depth_grid) {}

  std::size_t working_set_bytes() const override {
    return matcher_.working_set_bytes() + (obstacles_ ? obstacles_->working_set_bytes() : 0) +
           (grid_ ? grid_->working_set_bytes() : 0);
  }

  // What cannot start (an image of the wrong size) throws here, before a task is queued.
  void prepare(PairWork& work) override {
    if (!ran_last_) matcher_.reset_history();
    ran_last_ = false;  // stays so if start() throws: that pair had no disparity
    stripes_ = matcher_.start(work.result.left, work.result.right);
    ran_last_ = true;
  }
  int add_tasks(PairWork& work) override {
    result_ = &work.result;
    ground_next_ = protocol::has_stage(work.run, protocol::Stage::ground);
    stripes_left_.store(stripes_, std::memory_order_relaxed);
    return work.batch.add(stripes_, stripe_);
  }
  // A pair after one without disparity starts a new sequence.
  void skip(PairWork& /*work*/) override { ran_last_ = false; }
  void forget_history() override { ran_last_ = false; }

 private:
  void finish_dense(FrameResult& r) {
    r.disparity = matcher_.finish();
    std::uint64_t valid = 0;
    for (int y = 0; y < r.disparity.height(); ++y) {
      const std::int16_t* row = r.disparity.row(y);
      for (int x = 0; x < r.disparity.width(); ++x) valid += row[x] >= 0 ? 1 : 0;
    }
    r.valid_disparity_permille = static_cast<int>(
        valid * 1000 / (static_cast<std::uint64_t>(r.disparity.width()) * r.disparity.height()));
    r.disparity_confidence = matcher_.confidence();
    // With the ground stage, the sectors wait for the ground (stages/ground.cpp).
    if (obstacles_ && !ground_next_) {
      r.obstacles = &obstacles_->measure(r.disparity, r.frame, r.disparity_confidence);
    }
    if (grid_) r.depth_grid = &grid_->measure(r.disparity, r.frame, r.disparity_confidence);
  }

  struct Stripe {
    DisparityStage& s;
    void operator()(int i, int worker) const {
      s.matcher_.run_stripe(i, worker);
      if (s.stripes_left_.fetch_sub(1, std::memory_order_acq_rel) == 1) s.finish_dense(*s.result_);
    }
  };

  vision::StereoMatcher matcher_;
  ObstacleSectors* obstacles_;
  DepthGrid* grid_;
  bool ran_last_ = false;     // false: the next disparity starts a new sequence
  bool ground_next_ = false;  // the ground stage runs on this pair
  int stripes_ = 0;
  std::atomic<int> stripes_left_{0};
  FrameResult* result_ = nullptr;
  Stripe stripe_{*this};
};

}  // namespace

extern constinit const StageDefinition disparity_stage{make_stage<DisparityStage>};

}  // namespace epipole::firmware::stages
