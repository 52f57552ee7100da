// The trigger ledger: every trigger number settled once, into the cause that lost it.
#include "epipole/hal/trigger_ledger.hpp"

#include <gtest/gtest.h>

#include <cstdint>

namespace epipole::hal {
namespace {

TriggerAccount account(std::uint64_t published, std::uint64_t stale, std::uint64_t one_side,
                       std::uint64_t both_sides, std::uint64_t corrupt) {
  TriggerAccount a;
  a.published = published;
  a.stale = stale;
  a.one_side = one_side;
  a.both_sides = both_sides;
  a.corrupt = corrupt;
  return a;
}

TEST(TriggerLedger, SettlesEachNumberOnceIntoItsCause) {
  TriggerLedger ledger;
  // 0: published. 1: only the left frame came. 2: neither. 3: the right frame damaged, the
  // left one came. 4: paired but skipped. 5: both came and failed the checks. 6: published.
  ledger.seen(Side::left, 0);
  ledger.seen(Side::right, 0);
  ledger.published(0);
  ledger.seen(Side::left, 1);
  ledger.damaged(3);
  ledger.seen(Side::left, 3);
  ledger.seen(Side::left, 4);
  ledger.seen(Side::right, 4);
  ledger.stale(4);
  EXPECT_EQ(ledger.account(), account(1, 1, 1, 1, 1));
  EXPECT_EQ(ledger.next(), 5u);
  ledger.seen(Side::left, 5);
  ledger.seen(Side::right, 5);
  ledger.damaged(5);
  ledger.published(6);
  EXPECT_EQ(ledger.account(), account(2, 1, 1, 1, 2));
  EXPECT_EQ(ledger.account().published + ledger.account().dropped(), 7u);
}

TEST(TriggerLedger, AFrameAWindowLaterSettlesWhatCanNoLongerPair) {
  TriggerLedger ledger;
  // The right camera is gone: left frames come for 200 triggers, none pairs. Each is settled
  // as one-sided once a frame far enough after it came, before any pair is published.
  for (std::uint32_t n = 0; n < 200; ++n) ledger.seen(Side::left, n);
  const TriggerAccount& a = ledger.account();
  EXPECT_GT(a.one_side, 100u);
  EXPECT_EQ(a.both_sides, 0u);
  EXPECT_EQ(a.one_side, ledger.next());
  EXPECT_EQ(ledger.at_newest_published(), TriggerAccount{}) << "no pair published yet";
  ledger.seen(Side::left, 200);
  ledger.seen(Side::right, 200);
  ledger.published(200);
  EXPECT_EQ(ledger.account(), account(1, 0, 200, 0, 0));
  EXPECT_EQ(ledger.at_newest_published(), ledger.account());
  // Frames far ahead settle what is behind them, but the published account waits for a pair.
  ledger.seen(Side::left, 300);
  EXPECT_EQ(ledger.account().one_side, 200u);
  EXPECT_EQ(ledger.account().both_sides, 36u) << "201 .. 236";
  EXPECT_EQ(ledger.at_newest_published(), account(1, 0, 200, 0, 0));
}

TEST(TriggerLedger, ALongGapWithNoFramesIsLostOnBothSides) {
  TriggerLedger ledger;
  ledger.seen(Side::left, 3);  // 0..2 never came; 3 came on one side
  ledger.published(100'000);   // and nothing else until 100 000
  EXPECT_EQ(ledger.account(), account(1, 0, 1, 99'999, 0));
  EXPECT_EQ(ledger.next(), 100'001u);
}

TEST(TriggerLedger, FramesAfterTheirTriggerWasSettledAreIgnored) {
  TriggerLedger ledger;
  ledger.published(10);
  ledger.seen(Side::right, 7);  // too late: 7 was settled (lost on both sides) with 10
  ledger.damaged(9);
  ledger.published(11);
  EXPECT_EQ(ledger.account(), account(2, 0, 0, 10, 0));
}

TEST(TriggerLedger, NumbersWrapAround) {
  TriggerLedger ledger(0xFFFF'FFFEu);
  ledger.published(0xFFFF'FFFEu);
  ledger.seen(Side::left, 0xFFFF'FFFFu);
  ledger.published(1);  // 0xFFFFFFFF one-sided, 0 lost on both, 1 published
  EXPECT_EQ(ledger.account(), account(2, 0, 1, 1, 0));
  EXPECT_EQ(ledger.next(), 2u);
}

}  // namespace
}  // namespace epipole::hal
