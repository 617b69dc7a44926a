// The integration tests' child processes (tests/support/subprocess.h).
#include "subprocess.h"

#include <gtest/gtest.h>

#include <fcntl.h>
#include <unistd.h>

namespace whiskeye::testing {
namespace {

TEST(Subprocess, TheChildInheritsNoDescriptorOfTheTestButItsStandardStreams) {
  // A socket or file the test holds (its own LCM, say) must not become the child's: slamd counts the
  // receive drops of every UDP socket it holds.
  const int fd = ::open("/dev/null", O_RDONLY);  // not O_CLOEXEC
  ASSERT_GE(fd, 3);
  Subprocess child({"sh", "-c", "ls /proc/$$/fd"});  // the shell's descriptors, listed by a child of it
  ASSERT_EQ(child.wait(10), 0) << child.output();
  EXPECT_EQ(child.output(), "0\n1\n2\n");
  ::close(fd);
}

TEST(Subprocess, ReportsTheExitStatusAndTheSignalThatEndedTheChild) {
  Subprocess ok({"sh", "-c", "echo hello; exit 3"});
  EXPECT_EQ(ok.wait(10), 3);
  EXPECT_EQ(ok.output(), "hello\n");
  Subprocess killed({"sleep", "30"});
  killed.signal(SIGKILL);
  EXPECT_EQ(killed.wait(10), 128 + SIGKILL);
}

}  // namespace
}  // namespace whiskeye::testing
