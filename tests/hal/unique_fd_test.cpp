// The owning file descriptor: closed when its owner goes, moved not copied.
#include "epipole/hal/unique_fd.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <gtest/gtest.h>

#include <cerrno>
#include <utility>

namespace epipole::hal {
namespace {

bool is_open(int fd) {
  return ::fcntl(fd, F_GETFD) != -1 || errno != EBADF;
}

TEST(UniqueFd, ClosesWhatItOwnsOnceAndMovesOwnership) {
  int pipe_fds[2];
  ASSERT_EQ(::pipe(pipe_fds), 0);
  const int read_end = pipe_fds[0];
  const int write_end = pipe_fds[1];
  {
    UniqueFd a(read_end);
    EXPECT_TRUE(a);
    UniqueFd b(std::move(a));
    EXPECT_FALSE(a);  // NOLINT(bugprone-use-after-move): what a move leaves is the point
    EXPECT_EQ(b.get(), read_end);
    UniqueFd c;
    EXPECT_FALSE(c);
    c = std::move(b);
    EXPECT_EQ(c.get(), read_end);
    EXPECT_TRUE(is_open(read_end));
    c.reset(write_end);  // closes the read end, owns the write end
    EXPECT_FALSE(is_open(read_end));
    EXPECT_TRUE(is_open(write_end));
  }
  EXPECT_FALSE(is_open(write_end)) << "closed when its owner went";
}

}  // namespace
}  // namespace epipole::hal
