// End-to-end tests of the real `based` binary: a Robotino REST server on 127.0.0.1 in the test, the
// daemon as a subprocess, LCM over udpm:// inside a private network namespace (NETNS).
#include "fake_robotino.h"
#include "scratch.h"

#include "whiskeye/common/bus.h"
#include "whiskeye/common/clock.h"
#include "whiskeye/common/se2.h"

#include <whiskeye/base_cmd_t.hpp>
#include <whiskeye/driver_status_t.hpp>
#include <whiskeye/odometry_t.hpp>

#include <gtest/gtest.h>

#include <fcntl.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <sstream>
#include <thread>

extern char** environ;

namespace whiskeye::based {
namespace {

using testing::FakeRobotino;

const char* const kLcmUrl = "udpm://239.255.76.67:7667?ttl=0";

// The daemon as a child process, its stderr captured to a file.
class Daemon {
 public:
  explicit Daemon(const std::vector<std::string>& args) {
    stderr_path_ = whiskeye::testing::scratch_file("based_stderr", ".txt");
    std::vector<std::string> full{BASED_BINARY};
    full.insert(full.end(), args.begin(), args.end());
    std::vector<char*> argv;
    for (std::string& a : full) argv.push_back(a.data());
    argv.push_back(nullptr);
    posix_spawn_file_actions_t actions;
    posix_spawn_file_actions_init(&actions);
    posix_spawn_file_actions_addopen(&actions, 2, stderr_path_.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    const int rc = posix_spawn(&pid_, BASED_BINARY, &actions, nullptr, argv.data(), environ);
    posix_spawn_file_actions_destroy(&actions);
    if (rc != 0) pid_ = -1;
  }
  ~Daemon() {
    if (pid_ > 0 && !exited_) {
      ::kill(pid_, SIGKILL);
      ::waitpid(pid_, nullptr, 0);
    }
  }
  bool started() const { return pid_ > 0; }
  void signal(int sig) { ::kill(pid_, sig); }
  // Exit status, or -1 if still running after timeout_s (or killed by a signal).
  int wait_exit(double timeout_s) {
    const auto end = std::chrono::steady_clock::now() + std::chrono::duration<double>(timeout_s);
    while (std::chrono::steady_clock::now() < end) {
      int status = 0;
      if (::waitpid(pid_, &status, WNOHANG) == pid_) {
        exited_ = true;
        return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
    return -1;
  }
  std::string stderr_text() const {
    std::ifstream in(stderr_path_);
    std::stringstream s;
    s << in.rdbuf();
    return s.str();
  }

 private:
  pid_t pid_ = -1;
  bool exited_ = false;
  std::string stderr_path_;
};

std::string write_config(const std::string& text) {
  const std::string path = whiskeye::testing::scratch_file("based_test", ".yaml");
  std::ofstream(path) << text;
  return path;
}

const char* const kFastConfig =
    "odometry:\n  poll_rate_hz: 100\n  reply_timeout_s: 0.05\n"
    "command:\n  rate_hz: 50\n  deadman_s: 0.2\n  max_linear_accel: 2.0\n  max_angular_speed: 6.0\n"
    "  max_angular_accel: 20.0\n";

TEST(BasedDaemon, PublishesOdometryOverUdpmFollowsBaseCmdAndStopsOnSigterm) {
  FakeRobotino base;
  LcmBus bus(kLcmUrl);
  DecodeErrors errors;
  std::vector<odometry_t> odom;
  std::vector<driver_status_t> status;
  subscribe<odometry_t>(bus, "ODOMETRY", [&](const odometry_t& m) { odom.push_back(m); }, errors);
  subscribe<driver_status_t>(bus, "DRIVER_STATUS", [&](const driver_status_t& m) { status.push_back(m); }, errors);

  Daemon d({"--url", base.url(), "--lcm-url", kLcmUrl, "--config", write_config(kFastConfig)});
  ASSERT_TRUE(d.started());
  const auto end = std::chrono::steady_clock::now() + std::chrono::seconds(4);
  int64_t last_cmd_sent = 0;
  while (std::chrono::steady_clock::now() < end && (odom.size() < 30 || status.empty())) {
    bus.handle_timeout(20);
    if (monotonic_us() - last_cmd_sent > 20'000) {
      base_cmd_t c{};
      c.utime = now_utime();
      c.vy = 0.15;
      publish(bus, "BASE_CMD", c);
      last_cmd_sent = monotonic_us();
    }
  }
  ASSERT_GE(odom.size(), 30u) << d.stderr_text();
  ASSERT_FALSE(status.empty()) << d.stderr_text();
  std::vector<double> stamp_error_us;
  for (const odometry_t& m : odom) {
    const testing::FakePose p = FakeRobotino::expected_pose(m.seq);
    EXPECT_NEAR(m.x, p.x, 1e-12);
    EXPECT_NEAR(m.y, p.y, 1e-12);
    EXPECT_NEAR(m.theta, wrap_angle(p.theta), 1e-12);
    EXPECT_EQ(m.vy, p.vy);
    stamp_error_us.push_back(std::abs(static_cast<double>(m.utime - base.sample_utime(m.seq))));
  }
  // Stamped when the base sampled it: the median within 20 ms, none beyond 250 ms (one late wake-up
  // of a loaded runner is not a stamping error, a stamp a poll period or more off is).
  std::sort(stamp_error_us.begin(), stamp_error_us.end());
  EXPECT_LE(stamp_error_us[stamp_error_us.size() / 2], 20'000.0);
  EXPECT_LE(stamp_error_us.back(), 250'000.0);
  EXPECT_EQ(status.back().driver, "based");
  EXPECT_EQ(errors.total(), 0);
  bool moved = false;
  for (const auto& c : base.commands()) moved = moved || std::abs(c.vy - 0.15) < 1e-12;
  EXPECT_TRUE(moved) << "BASE_CMD did not reach the base";

  d.signal(SIGTERM);
  EXPECT_EQ(d.wait_exit(3.0), 0) << d.stderr_text();
  const auto cmds = base.commands();
  ASSERT_FALSE(cmds.empty());
  EXPECT_EQ(cmds.back().vx, 0.0);
  EXPECT_EQ(cmds.back().vy, 0.0) << "the last command before exit must stop the base";
  EXPECT_EQ(cmds.back().omega, 0.0);
  EXPECT_NE(d.stderr_text().find("signal 15"), std::string::npos) << d.stderr_text();
}

TEST(BasedDaemon, DrivesTheCircleFacingOutwardsAndExitsAfterTheLaps) {
  FakeRobotino base;
  const double radius = 0.1, speed = 0.4;
  Daemon d({"--url", base.url(), "--lcm-url", kLcmUrl, "--config", write_config(kFastConfig), "--circle",
            "0.1", "--speed", "0.4", "--laps", "1"});
  ASSERT_TRUE(d.started());
  EXPECT_EQ(d.wait_exit(5.0), 0) << d.stderr_text();
  const auto cmds = base.commands();
  ASSERT_GT(cmds.size(), 30u);
  double top = 0.0;
  for (const auto& c : cmds) {
    EXPECT_EQ(c.vx, 0.0);
    if (c.vy != 0.0) {
      EXPECT_NEAR(c.vy / c.omega, radius, 1e-9);
    }
    top = std::max(top, c.vy);
  }
  EXPECT_DOUBLE_EQ(top, speed);
  EXPECT_EQ(cmds.back().vy, 0.0);
  EXPECT_EQ(cmds.back().omega, 0.0);
  EXPECT_NE(d.stderr_text().find("circle finished"), std::string::npos) << d.stderr_text();
}

// A bad URL, circle or config is a usage or configuration error: exit 2 with one line (the unit
// does not restart on it).
TEST(BasedDaemon, BadInputExitsTwoWithAOneLineReason) {
  struct Case {
    std::vector<std::string> args;
    std::string says;
  };
  const std::vector<Case> cases = {
      {{"--url", "https://127.0.0.1:1"}, "http://"},
      {{"--url", "http://127.0.0.1:1", "--circle", "1.0"}, "--speed"},
      {{"--url", "http://127.0.0.1:1", "--config", write_config("command:\n  deadman: 1\n")}, "command.deadman"},
      {{"--url", "http://127.0.0.1:1", "--circle", "0.5", "--speed", "3.0"}, "max_linear_speed"},
  };
  for (const Case& c : cases) {
    std::vector<std::string> args = c.args;
    args.insert(args.end(), {"--lcm-url", kLcmUrl});
    Daemon d(args);
    ASSERT_TRUE(d.started());
    const int rc = d.wait_exit(3.0);
    EXPECT_EQ(rc, 2) << c.says;
    const std::string err = d.stderr_text();
    EXPECT_NE(err.find(c.says), std::string::npos) << err;
    EXPECT_EQ(err.rfind("based: ", 0), 0u) << err;
    EXPECT_EQ(std::count(err.begin(), err.end(), '\n'), 1) << err;
  }
}

}  // namespace
}  // namespace whiskeye::based
