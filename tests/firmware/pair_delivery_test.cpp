// How the frame loop hands pairs to an output: never waiting for the output's work, the freshest
// pair kept when the work is behind (the others counted dropped), the work's failures counted
// and gone past, health delivered beside the pairs.
#include "delivery/pair_delivery.hpp"

#include <gtest/gtest.h>

#include <future>
#include <stdexcept>
#include <string>
#include <vector>

#include "sim_rig.hpp"

namespace epipole::firmware::outputs {
namespace {

// A pair's results with its own left image (its pixels all `value`).
struct FakePair {
  GrayImage left;
  FrameResult result;
  FakePair(int w, int h, std::uint32_t frame, std::uint8_t value) : left(w, h) {
    for (int y = 0; y < h; ++y) std::fill_n(left.view().row(y), w, value);
    result.frame = frame;
    result.left = result.right = left.view();
  }
};

// Work that, at its first pair, says it has taken it and waits until released; it records what
// it saw.
struct HeldWork {
  std::promise<void> taken, release;
  std::shared_future<void> released = release.get_future().share();
  std::vector<std::uint32_t> frames;
  std::vector<std::uint8_t> first_pixels;
  void operator()(const PairCopy& pair) {
    if (frames.empty()) {
      taken.set_value();
      released.wait();
    }
    frames.push_back(pair.frame);
    first_pixels.push_back(pair.left(0, 0));
  }
};

TEST(PairDelivery, WorkThatIsBehindGetsTheFreshestPairAndTheOthersAreCountedDropped) {
  const test::SimRig rig(64, 16, 4);
  HeldWork held;
  PairDelivery delivery("test", rig.config, kRectified, [&](const PairCopy& p) { held(p); });
  delivery.start();
  FakePair first(64, 16, 1, 10);
  delivery.offer(first.result, {});
  held.taken.get_future().wait();
  // Nine more while the work holds the first: offer() copies and returns each time (were it to
  // wait for the work, this test would never end).
  for (std::uint32_t frame = 2; frame <= 10; ++frame) {
    FakePair pair(64, 16, frame, static_cast<std::uint8_t>(frame * 10));
    delivery.offer(pair.result, {});
  }
  held.release.set_value();
  delivery.stop();
  const DeliveryCounters c = delivery.counters();
  EXPECT_EQ(held.frames, (std::vector<std::uint32_t>{1, 10})) << "the newest is never dropped";
  EXPECT_EQ(held.first_pixels, (std::vector<std::uint8_t>{10, 100}))
      << "each its own copy, not the caller's buffer";
  EXPECT_EQ(c.delivered, 2u);
  EXPECT_EQ(c.dropped, 8u) << "2..9 each replaced by the next while waiting";
  EXPECT_EQ(c.failures, 0u);
}

TEST(PairDelivery, AFailureOfTheWorkIsCountedAndTheNextPairsAreDelivered) {
  const test::SimRig rig(64, 16, 4);
  std::vector<std::uint32_t> delivered;
  std::promise<void> third;
  PairDelivery delivery("test", rig.config, kRectified, [&](const PairCopy& p) {
    if (p.frame == 1) throw Error("disk full");
    delivered.push_back(p.frame);
    if (p.frame == 3) third.set_value();
  });
  delivery.start();
  for (std::uint32_t frame = 1; frame <= 3; ++frame) {
    FakePair pair(64, 16, frame, 1);
    delivery.offer(pair.result, {});
    if (frame == 1) {  // delivered one at a time: no drop to reason about
      while (delivery.counters().failures == 0) std::this_thread::yield();
    }
    if (frame == 2) {
      while (delivery.counters().delivered < 1) std::this_thread::yield();
    }
  }
  third.get_future().wait();
  delivery.stop();
  EXPECT_EQ(delivery.counters().failures, 1u);
  EXPECT_EQ(delivery.counters().delivered, 2u);
  EXPECT_EQ(delivered, (std::vector<std::uint32_t>{2, 3}));
}

TEST(PairDelivery, HealthReachesTheOutputsThatTakeIt) {
  const test::SimRig rig(64, 16, 4);
  std::promise<std::uint32_t> got;
  PairDelivery delivery(
      "test", rig.config, kRectified, [](const PairCopy&) {},
      [&](const HealthReport& h) { got.set_value(h.health.frames); });
  delivery.start();
  HealthReport health;
  health.health.frames = 42;
  delivery.offer_health(health);
  EXPECT_EQ(got.get_future().get(), 42u);
  delivery.stop();
}

TEST(PairDelivery, PairsAndHealthAreDoneInTheOrderTheyWereOffered) {
  const test::SimRig rig(64, 16, 4);
  HeldWork held;
  std::vector<std::string> order;
  PairDelivery delivery(
      "test", rig.config, kRectified,
      [&](const PairCopy& p) {
        held(p);
        order.push_back("pair " + std::to_string(p.frame));
      },
      [&](const HealthReport& h) { order.push_back("health " + std::to_string(h.health.frames)); });
  delivery.start();
  FakePair first(64, 16, 1, 1);
  delivery.offer(first.result, {});
  held.taken.get_future().wait();
  HealthReport health;
  health.health.frames = 7;
  delivery.offer_health(health);  // behind the work, which is always behind from here on
  for (std::uint32_t frame = 2; frame <= 4; ++frame) {
    FakePair pair(64, 16, frame, 1);
    delivery.offer(pair.result, {});
  }
  held.release.set_value();
  delivery.stop();
  EXPECT_EQ(order, (std::vector<std::string>{"pair 1", "health 7", "pair 4"}))
      << "health is never starved by pairs that keep coming";
}

TEST(PairDelivery, APairCopyHoldsOnlyThePartsAskedFor) {
  const test::SimRig rig(64, 16, 4);
  const PairCopy copy(rig.config, kRectified);
  EXPECT_EQ(copy.left.width(), 64);
  EXPECT_TRUE(copy.left_raw.empty());
  EXPECT_TRUE(copy.disparity.empty());
  EXPECT_EQ(copy.points.capacity(), 0u);
  const PairCopy all(rig.config, kRectified | kRaw | kDisparity | kPoints | kDetections);
  EXPECT_GT(all.working_set_bytes(), 5u * 64 * 16);
  EXPECT_GE(all.points.capacity(), static_cast<std::size_t>(rig.config.sparse.max_matches));
}

}  // namespace
}  // namespace epipole::firmware::outputs
