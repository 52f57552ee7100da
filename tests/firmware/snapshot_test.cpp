// The snapshot writer on its own: names never reused (across restarts too), the limit counted in
// the folder, a removed folder made again, and what each file says.
#include "epipole/firmware/snapshot.hpp"

#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <filesystem>
#include <fstream>
#include <memory>
#include <mutex>
#include <set>
#include <stdexcept>
#include <string>
#include <thread>

#include "sim_rig.hpp"

namespace epipole::firmware {
namespace {

constexpr int kW = 16, kH = 8;
constexpr std::chrono::milliseconds kWait{5000};

struct Pair {
  GrayImage image{kW, kH};
  FrameResult result(std::uint32_t frame) {
    FrameResult r;
    r.frame = frame;
    r.left_raw = r.right_raw = r.left = r.right = image.view();
    return r;
  }
};

std::set<std::string> files(const std::filesystem::path& folder) {
  std::set<std::string> names;
  for (const auto& e : std::filesystem::directory_iterator(folder)) {
    names.insert(e.path().filename().string());
  }
  return names;
}

TEST(Snapshots, NamesAreNeverReusedAcrossRestarts) {
  test::TempDir dir;
  const std::filesystem::path folder = dir.path() / "snapshots";
  std::filesystem::create_directories(folder);
  std::ofstream(folder / "snapshot-000007-left-raw.pgm") << "an older snapshot";
  Pair pair;
  {
    SnapshotWriter writer(folder, kW, kH);
    EXPECT_EQ(writer.count(), 1);
    ASSERT_TRUE(writer.take(pair.result(0), 1));
    ASSERT_TRUE(writer.flush(kWait));
    EXPECT_EQ(writer.written(), 1u);
  }
  {  // the firmware restarted: its frames count from 0 again
    SnapshotWriter writer(folder, kW, kH);
    ASSERT_TRUE(writer.take(pair.result(0), 1));
    ASSERT_TRUE(writer.flush(kWait));
    EXPECT_EQ(writer.count(), 3);
  }
  const std::set<std::string> names = files(folder);
  EXPECT_EQ(names.count("snapshot-000008-left-raw.pgm"), 1u);
  EXPECT_EQ(names.count("snapshot-000009-left-raw.pgm"), 1u);
  EXPECT_EQ(names.count("snapshot-000009-right.pgm"), 1u);
  std::ifstream older(folder / "snapshot-000007-left-raw.pgm");
  std::string text;
  std::getline(older, text);
  EXPECT_EQ(text, "an older snapshot") << "never overwritten";
  // Each file names its frame.
  std::ifstream pgm(folder / "snapshot-000009-left.pgm");
  std::string magic, comment;
  std::getline(pgm, magic);
  std::getline(pgm, comment);
  EXPECT_EQ(magic, "P5");
  EXPECT_EQ(comment, "# epipole frame 0");
}

TEST(Snapshots, TheLimitCountsTheFilesInTheFolderAndARemovedFolderIsMadeAgain) {
  test::TempDir dir;
  const std::filesystem::path folder = dir.path() / "snapshots";
  Pair pair;
  SnapshotWriter writer(folder, kW, kH, {.max_count = 2, .min_free_bytes = 0});
  for (std::uint32_t frame = 0; frame < 2; ++frame) {
    ASSERT_TRUE(writer.take(pair.result(frame), 1));
    ASSERT_TRUE(writer.flush(kWait));
  }
  EXPECT_EQ(writer.can_take(), SnapshotRefusal::limit);
  // Removed by hand: room again.
  for (const std::string& name : files(folder)) {
    if (name.starts_with("snapshot-000000-")) std::filesystem::remove(folder / name);
  }
  EXPECT_EQ(writer.can_take(), SnapshotRefusal::none);
  // The whole folder removed: made again by the next snapshot, numbered on.
  std::filesystem::remove_all(folder);
  ASSERT_TRUE(writer.take(pair.result(5), 2));
  ASSERT_TRUE(writer.flush(kWait));
  EXPECT_EQ(writer.failures(), 0u);
  EXPECT_EQ(files(folder).count("snapshot-000002-left-raw.pgm"), 1u);
  const std::optional<SnapshotDone> done = writer.finished();
  ASSERT_TRUE(done.has_value());
  EXPECT_EQ(done->sequence, 2);
  EXPECT_TRUE(done->ok);
}

// A folder that cannot be listed is neither counted as empty nor numbered from 0: refused.
TEST(Snapshots, AFolderThatCannotBeListedIsRefusedNotTakenForEmpty) {
  test::TempDir dir;
  const std::filesystem::path folder = dir.path() / "snapshots";
  Pair pair;
  SnapshotWriter writer(folder, kW, kH, {.max_count = 1, .min_free_bytes = 0});
  ASSERT_TRUE(writer.take(pair.result(0), 1));
  ASSERT_TRUE(writer.flush(kWait));
  EXPECT_EQ(writer.can_take(), SnapshotRefusal::limit);
  // Replaced by a file (opendir fails with ENOTDIR, as root too).
  std::filesystem::remove_all(folder);
  std::ofstream(folder) << "not a folder";
  EXPECT_EQ(writer.count(), std::nullopt);
  EXPECT_EQ(writer.can_take(), SnapshotRefusal::unreadable);
  EXPECT_FALSE(writer.take(pair.result(1), 2));
  // A writer started on it says why.
  EXPECT_THROW(SnapshotWriter(folder, kW, kH), Error);
  std::filesystem::remove(folder);
  EXPECT_EQ(writer.count(), 0) << "a missing folder holds none";
  EXPECT_EQ(writer.can_take(), SnapshotRefusal::none);
}

// A file system that stalls (a dying SD card): flush() gives up after its timeout, and the
// writer's destructor returns without waiting for the write (SIGTERM is not held up); the
// thread finishes it on its own.
TEST(Snapshots, AStalledWriteIsGivenUpByFlushAndDoesNotHoldUpTheStop) {
  test::TempDir dir;
  const std::filesystem::path folder = dir.path() / "snapshots";
  struct Gate {
    std::mutex mutex;
    std::condition_variable open;
    bool released = false;
    std::atomic<bool> entered{false};
  };
  const auto gate = std::make_shared<Gate>();
  Pair pair;
  {
    SnapshotWriter writer(folder, kW, kH, {.max_count = 10, .min_free_bytes = 0});
    writer.before_each_write([gate] {
      gate->entered = true;
      std::unique_lock lock(gate->mutex);
      gate->open.wait(lock, [&] { return gate->released; });
    });
    ASSERT_TRUE(writer.take(pair.result(3), 9));
    EXPECT_FALSE(writer.flush(std::chrono::milliseconds(200)));
    EXPECT_TRUE(gate->entered);
    EXPECT_EQ(writer.can_take(), SnapshotRefusal::busy);
    EXPECT_FALSE(writer.finished().has_value());
  }  // the destructor waits SnapshotWriter::kStopWait, then leaves the write to its thread
  {
    const std::lock_guard lock(gate->mutex);
    EXPECT_FALSE(gate->released) << "the stop did not wait for the write to end";
    gate->released = true;
  }
  gate->open.notify_all();
  const auto end = std::chrono::steady_clock::now() + std::chrono::seconds(10);
  while (!std::filesystem::exists(folder / "snapshot-000000-right.pgm") &&
         std::chrono::steady_clock::now() < end) {
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  EXPECT_TRUE(std::filesystem::exists(folder / "snapshot-000000-right.pgm"))
      << "the thread finished the write";
  std::this_thread::sleep_for(std::chrono::milliseconds(100));  // and its sync
}

// An exception on the writer thread (what the file system's code did not foresee) is a failed
// snapshot, answered as such; the thread goes on and writes the next.
TEST(Snapshots, AnExceptionWhileWritingIsAFailedSnapshotAndTheNextIsWritten) {
  test::TempDir dir;
  Pair pair;
  SnapshotWriter writer(dir.path() / "snapshots", kW, kH, {.max_count = 10, .min_free_bytes = 0});
  auto calls = std::make_shared<std::atomic<int>>(0);
  writer.before_each_write([calls] {
    if ((*calls)++ == 0) throw std::runtime_error("the card's driver gave up");
  });
  ::testing::internal::CaptureStderr();
  ASSERT_TRUE(writer.take(pair.result(1), 4));
  ASSERT_TRUE(writer.flush(kWait));
  const std::string journal = ::testing::internal::GetCapturedStderr();
  EXPECT_NE(journal.find("snapshot: the card's driver gave up"), std::string::npos) << journal;
  std::optional<SnapshotDone> done = writer.finished();
  ASSERT_TRUE(done.has_value());
  EXPECT_EQ(done->sequence, 4);
  EXPECT_FALSE(done->ok);
  EXPECT_EQ(writer.failures(), 1u);
  ASSERT_TRUE(writer.take(pair.result(2), 5));
  ASSERT_TRUE(writer.flush(kWait));
  done = writer.finished();
  ASSERT_TRUE(done.has_value());
  EXPECT_TRUE(done->ok);
  EXPECT_EQ(writer.written(), 1u);
}

}  // namespace
}  // namespace epipole::firmware
