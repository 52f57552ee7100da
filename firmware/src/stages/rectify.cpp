// Rectification: both images remapped with the rig's calibration, in row bands on the pool,
// before every other stage (they read it); the next pair, when it has come, is taken and
// rectified ahead into a second set of images in the workers' last gaps (NextPair).
#include <array>

#include "epipole/core/error.hpp"
#include "epipole/firmware/rig_correction.hpp"
#include "epipole/firmware/stereo_rectification.hpp"
#include "stage_files.hpp"
#include "steady_time.hpp"

namespace epipole::firmware::stages {

namespace {

using detail::steady_now;

class RectifyStage final : public PipelineStage {
 public:
  explicit RectifyStage(const StageContext& c) : pool_(c.pool), correction_(c.correction) {
    if (!c.calibration) return;
    const BoardConfig& board = c.board;
    require(c.calibration->width == board.width() && c.calibration->height == board.height(),
            "calibration ", board.calibration.string(), " is for ", c.calibration->width, "x",
            c.calibration->height, " images but the cameras deliver ", board.width(), "x",
            board.height());
    rectifiers_.emplace(make_stereo_rectifiers(*c.calibration, c.path, 0, /*own_output=*/false));
    for (std::size_t slot = 0; slot < 2; ++slot) {
      left_[slot] = GrayImage(board.width(), board.height());
      right_[slot] = GrayImage(board.width(), board.height());
    }
  }

  bool available() const override { return rectifiers_.has_value(); }
  std::size_t working_set_bytes() const override {
    if (!rectifiers_) return 0;
    std::size_t images = 0;
    for (std::size_t slot = 0; slot < 2; ++slot) {
      images += left_[slot].size_bytes() + right_[slot].size_bytes();
    }
    // With the spare map a corrected rig's is rebuilt in.
    const std::size_t spare = correction_ != nullptr ? correction_->working_set_bytes() : 0;
    return rectifiers_->left.working_set_bytes() + rectifiers_->right.working_set_bytes() + images +
           spare;
  }

  // The pair rectified ahead when it is this one, else rectified now.
  void prepare(PairWork& work) override {
    FrameResult& r = work.result;
    hal::Nanoseconds& time = r.times[static_cast<std::size_t>(protocol::Stage::rectify)];
    // A corrected right map, rebuilt beside: in place now, and the pair ahead (rectified with
    // the old one) rectified again.
    if (correction_ != nullptr && rectifiers_ && correction_->install(rectifiers_->right)) {
      ahead_.ready = false;
    }
    const bool was_ahead = ahead_.matches(r.left_raw, r.right_raw, r.frame);
    ahead_.ready = false;  // used now, or never
    if (was_ahead) {
      slot_ = ahead_.slot;
      time = ahead_.rectify_ns;
      ++used_;
    } else {
      const hal::Nanoseconds start = steady_now();
      const GrayView left = r.left_raw, right = r.right_raw;
      pool_.run(2 * pool_.threads(),
                [&](int task, int) { rectify_band(left, right, slot_, task); });
      time = steady_now() - start;
    }
    r.left = left_[static_cast<std::size_t>(slot_)].view();
    r.right = right_[static_cast<std::size_t>(slot_)].view();
  }

  // A pair without rectification: the pair taken ahead will not be used; a corrected map is put
  // in place all the same (a rebuild never waits for rectification to be switched on again).
  void skip(PairWork& /*work*/) override {
    ahead_.ready = false;
    if (correction_ != nullptr && rectifiers_) correction_->install(rectifiers_->right);
  }

  // The next pair, when it is there and of the images' size (one that is not is rectified, and
  // refused, when it is processed itself), into the other slot, in as many row bands per image
  // as there are workers. It counts as rectified ahead only once the whole batch has run.
  void fill_gaps(PairWork& work) override {
    took_next_ = false;
    ahead_part_ = TaskBatch::kNoPart;
    if (work.next == nullptr || !protocol::has_stage(work.run, protocol::Stage::rectify)) return;
    next_ = work.next;
    size_ = work.result.left_raw;
    ahead_slot_ = 1 - slot_;
    ahead_part_ = work.batch.add(2 * pool_.threads(), rectify_next_, work.batch.add(1, take_next_));
  }

  void finish(PairWork& work) override {
    if (!took_next_) return;
    ahead_.slot = ahead_slot_;
    ahead_.rectify_ns = work.batch.span_ns(ahead_part_, ahead_part_);
    ahead_.ready = true;
    ++done_;
  }

  void forget_history() override { ahead_.ready = false; }
  void drop_pair_ahead() override { ahead_.ready = false; }
  AheadCounts ahead() const override { return {done_, used_}; }

 private:
  struct PairAhead {
    NextPair::Images images;
    int slot = 0;
    hal::Nanoseconds rectify_ns = 0;
    bool ready = false;
    bool matches(GrayView left, GrayView right, std::uint32_t frame) const {
      const auto same = [](GrayView a, GrayView b) {
        return a.data() == b.data() && a.width() == b.width() && a.height() == b.height() &&
               a.stride() == b.stride();
      };
      return ready && images.frame == frame && same(images.left, left) && same(images.right, right);
    }
  };

  // Task `task` of 2 x threads rectifying a pair into `slot`: one row band of one image (even
  // tasks the left, odd the right), as many bands per image as there are workers.
  void rectify_band(GrayView left_raw, GrayView right_raw, int slot, int task) {
    const auto s = static_cast<std::size_t>(slot);
    const int bands = pool_.threads();
    const int band = task / 2;
    const int height = left_[s].height();
    const int first = band * height / bands;
    const int end = (band + 1) * height / bands;
    if (task % 2 == 0) {
      rectifiers_->left.rectify_rows(left_raw, left_[s].view(), first, end);
    } else {
      rectifiers_->right.rectify_rows(right_raw, right_[s].view(), first, end);
    }
  }

  struct TakeNext {
    RectifyStage& s;
    void operator()(int, int) const {
      const std::optional<NextPair::Images> images = s.next_->take();
      const auto fits = [&](GrayView image) {
        return image.width() == s.size_.width() && image.height() == s.size_.height();
      };
      if (images && fits(images->left) && fits(images->right)) {
        s.ahead_.images = *images;
        s.took_next_ = true;
      }
    }
  };
  struct RectifyNext {
    RectifyStage& s;
    void operator()(int task, int) const {
      if (s.took_next_) {
        s.rectify_band(s.ahead_.images.left, s.ahead_.images.right, s.ahead_slot_, task);
      }
    }
  };

  ThreadPool& pool_;
  RigCorrection* correction_;
  std::optional<StereoRectifiers> rectifiers_;
  // Two rectified images per camera: the current pair's and the one ahead.
  std::array<GrayImage, 2> left_, right_;
  int slot_ = 0;  // the current pair's
  PairAhead ahead_;
  NextPair* next_ = nullptr;
  GrayView size_;  // of the current pair's images
  int ahead_slot_ = 1;
  int ahead_part_ = TaskBatch::kNoPart;
  bool took_next_ = false;
  TakeNext take_next_{*this};
  RectifyNext rectify_next_{*this};
  std::uint64_t done_ = 0, used_ = 0;
};

}  // namespace

extern constinit const StageDefinition rectify_stage{make_stage<RectifyStage>};

}  // namespace epipole::firmware::stages
