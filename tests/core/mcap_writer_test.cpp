// The MCAP writer when the disk says no: a write that fails is an error naming the file, the file
// is left closed with what it had, and the writer records into the next file as if nothing
// happened (the recording output then opens one through its ring).
#include "epipole/core/mcap_writer.hpp"

#include <gtest/gtest.h>
#include <sys/resource.h>

#include <csignal>
#include <fstream>
#include <string>

#include "epipole/core/temporary_folder.hpp"
#include "error_of.hpp"

namespace epipole::mcap {
namespace {

bool ends_with_magic(const std::filesystem::path& file) {
  std::ifstream in(file, std::ios::binary);
  in.seekg(-8, std::ios::end);
  char magic[8] = {};
  in.read(magic, 8);
  return in && std::string(magic, 8) == std::string("\x89MCAP0\r\n", 8);
}

// A file size limit for the test's duration (writes past it fail with EFBIG, not a signal).
struct FileSizeLimit {
  rlimit before{};
  void (*handler)(int) = nullptr;
  explicit FileSizeLimit(rlim_t bytes) {
    getrlimit(RLIMIT_FSIZE, &before);
    handler = std::signal(SIGXFSZ, SIG_IGN);
    const rlimit limit{bytes, before.rlim_max};
    setrlimit(RLIMIT_FSIZE, &limit);
  }
  ~FileSizeLimit() {
    setrlimit(RLIMIT_FSIZE, &before);
    std::signal(SIGXFSZ, handler);
  }
};

// Messages of noise (that zstd cannot shrink).
void write_messages(Writer& w, int count, std::size_t bytes) {
  std::uint32_t state = 12345;
  for (int i = 0; i < count; ++i) {
    std::vector<std::uint8_t>& out =
        w.begin_message(0, static_cast<std::uint32_t>(i), static_cast<std::uint64_t>(i) * 1000, 0);
    for (std::size_t b = 0; b < bytes; ++b) {
      state = state * 1664525u + 1013904223u;
      out.push_back(static_cast<std::uint8_t>(state >> 24));
    }
    w.end_message();
  }
}

TEST(McapWriter, AFailedWriteClosesTheFileAndTheNextFileIsWhole) {
  const TemporaryFolder dir("epipole-test");
  Writer w({{"t", "ros2msg", "uint8[] data\n"}}, {{1, "/t", "cdr", {}}}, 64 * 1024, 64 * 1024);
  w.open(dir.path() / "first.mcap", "test");
  std::string error;
  {
    const FileSizeLimit limit(200 * 1024);
    error = test::error_of([&] { write_messages(w, 200, 16 * 1024); });
  }
  EXPECT_NE(error.find((dir.path() / "first.mcap").string() + ": cannot write"), std::string::npos)
      << error;
  EXPECT_FALSE(w.is_open()) << "closed: the next message needs a file";
  EXPECT_NE(test::error_of([&] { write_messages(w, 1, 10); }).find("no file open"),
            std::string::npos);
  w.open(dir.path() / "second.mcap", "test");
  write_messages(w, 20, 16 * 1024);
  w.close();
  EXPECT_TRUE(ends_with_magic(dir.path() / "second.mcap"));
  EXPECT_FALSE(ends_with_magic(dir.path() / "first.mcap")) << "cut short where it failed";
}

TEST(McapWriter, AFileThatExistsIsNeverOverwritten) {
  const TemporaryFolder dir("epipole-test");
  std::ofstream(dir.path() / "there.mcap") << "keep";
  Writer w({{"t", "ros2msg", "uint8[] data\n"}}, {{1, "/t", "cdr", {}}}, 1024, 1024);
  EXPECT_NE(
      test::error_of([&] { w.open(dir.path() / "there.mcap", "test"); }).find("cannot create"),
      std::string::npos);
  std::ifstream in(dir.path() / "there.mcap");
  std::string kept;
  in >> kept;
  EXPECT_EQ(kept, "keep");
}

// The chunk index holds kMaxChunks chunks; chunks_left() says how many more the file takes before
// it would grow (its owner then starts a new file).
TEST(McapWriter, SaysHowManyChunksTheFileTakesBeforeItsIndexGrows) {
  const TemporaryFolder dir("epipole-test");
  Writer w({{"t", "ros2msg", "uint8[] data\n"}}, {{1, "/t", "cdr", {}}}, 1024, 1024);
  w.open(dir.path() / "chunks.mcap", "test");
  EXPECT_EQ(w.chunks_left(), Writer::kMaxChunks);
  write_messages(w, 10, 2048);  // each message fills a chunk of 1 KiB
  EXPECT_EQ(w.chunks_left(), Writer::kMaxChunks - 10);
  w.close();
  w.open(dir.path() / "next.mcap", "test");
  EXPECT_EQ(w.chunks_left(), Writer::kMaxChunks) << "a new file, a new index";
  w.close();
}

}  // namespace
}  // namespace epipole::mcap
