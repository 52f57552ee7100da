#include "epipole/firmware/command_memory.hpp"

#include <gtest/gtest.h>

namespace epipole::firmware {
namespace {

using protocol::AckReason;
using protocol::AckStatus;
constexpr hal::Nanoseconds kSecond = 1'000'000'000;

TEST(CommandMemory, AResendIsTheSameNumberAndContentWithinTheWindow) {
  CommandMemory memory;
  const protocol::Message exposure = protocol::SetExposure{4000, 0};
  const CommandVerdict rejected{AckStatus::rejected, AckReason::timing};
  memory.remember(7, exposure, 10 * kSecond, rejected);
  const CommandMemory::Entry* first = memory.resent(7, exposure, 11 * kSecond);
  ASSERT_NE(first, nullptr);
  EXPECT_EQ(first->verdict, rejected);
  EXPECT_EQ(memory.resent(7, protocol::SetExposure{4001, 0}, 11 * kSecond), nullptr)
      << "other content: a number reused by a robot that rebooted";
  EXPECT_EQ(memory.resent(8, exposure, 11 * kSecond), nullptr) << "another number";
  EXPECT_EQ(memory.resent(7, exposure, 10 * kSecond + CommandMemory::kResendWindow + 1), nullptr)
      << "too late for a resend: a new command";
  // The number used again with other content: only the newest stands.
  memory.remember(7, protocol::SetExposure{5000, 0}, 12 * kSecond, {});
  EXPECT_EQ(memory.resent(7, exposure, 12 * kSecond), nullptr);
  EXPECT_NE(memory.resent(7, protocol::SetExposure{5000, 0}, 12 * kSecond), nullptr);
}

TEST(CommandMemory, APendingSnapshotIsSettledAndTheOldestCommandsAreForgotten) {
  CommandMemory memory;
  const protocol::Message snapshot = protocol::Snapshot{};
  memory.remember(1, snapshot, 0, {}, true);
  EXPECT_TRUE(memory.resent(1, snapshot, 1)->pending);
  memory.settle(1, {AckStatus::rejected, AckReason::failed});
  EXPECT_FALSE(memory.resent(1, snapshot, 2)->pending);
  EXPECT_EQ(memory.resent(1, snapshot, 2)->verdict.reason, AckReason::failed);
  for (std::uint16_t n = 2; n < 2 + CommandMemory::kSize; ++n) {
    memory.remember(n, protocol::SetStages{n}, 3, {});
  }
  EXPECT_EQ(memory.resent(1, snapshot, 4), nullptr) << "the oldest of 17";
  EXPECT_NE(memory.resent(2, protocol::SetStages{2}, 4), nullptr);
}

}  // namespace
}  // namespace epipole::firmware
