// The recordings' folder: a new file always fits the bounds (the oldest recordings go first),
// only the ring's own files are ever removed, and no room at all is an error naming the folder.
#include "record/recording_ring.hpp"

#include <gtest/gtest.h>

#include <fstream>
#include <string>

#include "error_of.hpp"
#include "sim_rig.hpp"

namespace epipole::firmware::record {
namespace {

namespace fs = std::filesystem;

void write_file(const fs::path& file, std::size_t bytes) {
  std::ofstream(file, std::ios::binary) << std::string(bytes, 'x');
}

constexpr std::int64_t kSecond = 1'000'000'000;
constexpr std::int64_t kDec7 = 1796633000 * kSecond;  // 2026-12-07T08:43:20Z

TEST(RecordingRing, NamesFilesByTheirUtcTimeAndNeverReusesOne) {
  const test::TempDir dir;
  RecordingRing ring(dir.path() / "rec", {1 << 10, 1 << 20, 0});
  const fs::path first = ring.next_file(kDec7);
  EXPECT_EQ(first.filename(), "epipole-20261207T084320Z.mcap");
  EXPECT_TRUE(fs::is_directory(dir.path() / "rec")) << "the folder is made";
  write_file(first, 10);
  EXPECT_EQ(ring.next_file(kDec7).filename(), "epipole-20261207T084320Z-1.mcap");
}

TEST(RecordingRing, TheOldestRecordingsGoUntilTheNextFileFits) {
  const test::TempDir dir;
  const fs::path folder = dir.path() / "rec";
  fs::create_directories(folder);
  for (int i = 0; i < 5; ++i) {
    write_file(folder / ("epipole-2026120" + std::to_string(i + 1) + "T000000Z.mcap"), 1000);
  }
  write_file(folder / "notes.txt", 5000);  // not a recording: never removed, not counted
  RecordingRing ring(folder, {1000, 4000, 0});
  ring.next_file(kDec7);
  EXPECT_EQ(ring.removed(), 2u) << "5 x 1000 + the next 1000 must fit in 4000";
  EXPECT_FALSE(fs::exists(folder / "epipole-20261201T000000Z.mcap"));
  EXPECT_FALSE(fs::exists(folder / "epipole-20261202T000000Z.mcap"));
  EXPECT_TRUE(fs::exists(folder / "epipole-20261203T000000Z.mcap"));
  EXPECT_TRUE(fs::exists(folder / "notes.txt"));
}

TEST(RecordingRing, NoRoomEvenWithoutRecordingsIsAnErrorNamingTheFolder) {
  const test::TempDir dir;
  const fs::path folder = dir.path() / "rec";
  fs::create_directories(folder);
  write_file(folder / "epipole-20261201T000000Z.mcap", 1000);
  // More free space than any file system has.
  RecordingRing ring(folder, {1000, 1ull << 40, 1ull << 62});
  const std::string error = test::error_of([&] { ring.next_file(kDec7); });
  EXPECT_NE(error.find(folder.string() + ": no room for another recording"), std::string::npos)
      << error;
  EXPECT_EQ(ring.removed(), 0u) << "no recording is removed when that would not make room";
  EXPECT_TRUE(fs::exists(folder / "epipole-20261201T000000Z.mcap"));
}

TEST(RecordingRing, RecordingsOfOneSecondGoInTheOrderTheyWereMade) {
  const test::TempDir dir;
  const fs::path folder = dir.path() / "rec";
  fs::create_directories(folder);
  for (const char* name : {"epipole-20261201T000000Z.mcap", "epipole-20261201T000000Z-1.mcap",
                           "epipole-20261201T000000Z-2.mcap", "epipole-20261201T000000Z-10.mcap"}) {
    write_file(folder / name, 1000);
  }
  RecordingRing ring(folder, {1000, 3000, 0});
  ring.next_file(kDec7);
  EXPECT_EQ(ring.removed(), 2u);
  EXPECT_FALSE(fs::exists(folder / "epipole-20261201T000000Z.mcap")) << "the first made";
  EXPECT_FALSE(fs::exists(folder / "epipole-20261201T000000Z-1.mcap"));
  EXPECT_TRUE(fs::exists(folder / "epipole-20261201T000000Z-2.mcap"));
  EXPECT_TRUE(fs::exists(folder / "epipole-20261201T000000Z-10.mcap")) << "the last made";
}

TEST(RecordingRing, AFolderThatCannotBeMadeIsAnError) {
  const test::TempDir dir;
  write_file(dir.path() / "file", 1);
  RecordingRing ring(dir.path() / "file" / "rec", {});
  EXPECT_NE(test::error_of([&] { ring.next_file(kDec7); }).find("cannot make the folder"),
            std::string::npos);
}

}  // namespace
}  // namespace epipole::firmware::record
