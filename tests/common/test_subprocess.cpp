// The integration tests' child processes (tests/support/subprocess.h).
#include "subprocess.h"

#include <gtest/gtest.h>

#include <fcntl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <fstream>
#include <string>

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

// Whether `pid` is gone or a zombie nobody has reaped yet (it no longer runs either way).
bool ended(pid_t pid) {
  std::ifstream stat("/proc/" + std::to_string(pid) + "/stat");
  std::string line;
  if (!std::getline(stat, line)) return true;
  const auto close = line.rfind(')');
  return close == std::string::npos || line.substr(close + 2, 1) == "Z";
}

TEST(Subprocess, AChildEndsWhenTheTestProcessIsKilledWithoutCleaningUp) {
  int to_test[2];
  ASSERT_EQ(::pipe(to_test), 0);
  // Stands in for a test process: it starts a child and is then SIGKILLed, so no destructor runs.
  const pid_t test_process = ::fork();
  ASSERT_GE(test_process, 0);
  if (test_process == 0) {
    ::close(to_test[0]);
    Subprocess child({"sleep", "120"});
    const pid_t pid = child.pid();
    if (::write(to_test[1], &pid, sizeof pid) != static_cast<ssize_t>(sizeof pid)) std::_Exit(1);
    for (;;) ::pause();
  }
  ::close(to_test[1]);
  pid_t child = -1;
  ASSERT_EQ(::read(to_test[0], &child, sizeof child), static_cast<ssize_t>(sizeof child));
  ::close(to_test[0]);
  ASSERT_GT(child, 0);
  EXPECT_FALSE(ended(child)) << "the child runs while the test process does";

  ::kill(test_process, SIGKILL);
  ::waitpid(test_process, nullptr, 0);
  const bool gone = wait_until([&] { return ended(child); }, 10.0);
  EXPECT_TRUE(gone) << "child " << child << " outlived the test process";
  if (!gone) ::kill(child, SIGKILL);
}

TEST(Subprocess, AChildOfALiveTestRunsUntilStopped) {
  Subprocess child({"sleep", "120"});
  EXPECT_FALSE(wait_until([&] { return ended(child.pid()); }, 0.5));
  EXPECT_EQ(child.stop(5.0, SIGTERM), 128 + SIGTERM);
}

}  // namespace
}  // namespace whiskeye::testing
