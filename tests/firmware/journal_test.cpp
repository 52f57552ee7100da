// The journal's stream is recognised by its device and inode (systemd.exec(5), JOURNAL_STREAM).
#include "epipole/firmware/journal.hpp"

#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <string>

namespace epipole::firmware {
namespace {

std::string stream_of(int fd) {
  struct stat file {};
  EXPECT_EQ(::fstat(fd, &file), 0);
  return std::to_string(file.st_dev) + ":" + std::to_string(file.st_ino);
}

TEST(Journal, TheStreamIsTheFileOfThatDeviceAndInode) {
  int first[2];
  int second[2];
  ASSERT_EQ(::pipe(first), 0);
  ASSERT_EQ(::pipe(second), 0);
  const std::string value = stream_of(first[1]);
  EXPECT_TRUE(names_stream(value.c_str(), first[1]));
  EXPECT_FALSE(names_stream(value.c_str(), second[1])) << "another file: a terminal, a log file";
  EXPECT_FALSE(names_stream(nullptr, first[1])) << "not run by systemd";
  EXPECT_FALSE(names_stream("", first[1]));
  EXPECT_FALSE(names_stream("12", first[1]));
  EXPECT_FALSE(names_stream((value + "x").c_str(), first[1]));
  EXPECT_FALSE(names_stream("junk:1", first[1]));
  EXPECT_FALSE(names_stream(value.c_str(), 999)) << "a descriptor that is not open";
  for (int fd : {first[0], first[1], second[0], second[1]}) ::close(fd);
}

// A robot sending refused commands in a loop gets one journal line a second, each saying how
// many were left out before it.
TEST(JournalEpisodes, AFlappingFaultIsSaidOnceAnIntervalItsEndOnlyWithItsStart) {
  constexpr std::int64_t kS = 1'000'000'000;
  JournalEpisodes lines(10 * kS);
  EXPECT_TRUE(lines.begins(0));
  EXPECT_TRUE(lines.end_is_said());
  EXPECT_EQ(lines.left_out(), 0u);
  EXPECT_FALSE(lines.begins(2 * kS));
  EXPECT_FALSE(lines.end_is_said()) << "nor its end";
  EXPECT_FALSE(lines.begins(5 * kS));
  EXPECT_TRUE(lines.begins(11 * kS));
  EXPECT_TRUE(lines.end_is_said());
  EXPECT_EQ(lines.left_out(), 2u);
}

TEST(JournalLimit, OneLineAnIntervalAndHowManyWereLeftOut) {
  constexpr std::int64_t kSecond = 1'000'000'000;
  JournalLimit limit(kSecond);
  EXPECT_TRUE(limit.allow(5 * kSecond));
  EXPECT_EQ(limit.left_out(), 0u);
  for (int i = 1; i <= 99; ++i) EXPECT_FALSE(limit.allow(5 * kSecond + i * 10'000'000));
  EXPECT_TRUE(limit.allow(6 * kSecond));
  EXPECT_EQ(limit.left_out(), 99u);
  EXPECT_FALSE(limit.allow(6 * kSecond + 1));
  EXPECT_TRUE(limit.allow(9 * kSecond));
  EXPECT_EQ(limit.left_out(), 1u);
}

}  // namespace
}  // namespace epipole::firmware
