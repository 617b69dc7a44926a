// The daemons as processes on the host (no CAN or video here): --help, bad configuration, a missing
// CAN interface, and camerad waiting for a missing camera while reporting READY to systemd and
// DEGRADED on DRIVER_STATUS. Runs in a private network namespace (udpm:// on loopback).
#include "scratch.h"

#include <gtest/gtest.h>
#include <signal.h>
#include <sys/socket.h>
#include <sys/un.h>
#include <sys/wait.h>
#include <unistd.h>

#include <whiskeye/common/bus.h>
#include <whiskeye/common/clock.h>
#include <whiskeye/driver_status_t.hpp>

#include <cstdlib>
#include <fstream>
#include <string>
#include <vector>

using namespace whiskeye;

namespace {

struct ProcessResult {
  int status = -1;
  std::string err;
};

// Runs argv with stderr captured; kills it after timeout_s.
ProcessResult run(const std::vector<std::string>& args, double timeout_s = 10) {
  const std::string err_path = whiskeye::testing::scratch_file("daemon_err", ".txt");
  const pid_t pid = fork();
  if (pid == 0) {
    FILE* f = std::freopen(err_path.c_str(), "w", stderr);
    (void)f;
    std::vector<char*> argv;
    for (const auto& a : args) argv.push_back(const_cast<char*>(a.c_str()));
    argv.push_back(nullptr);
    execv(argv[0], argv.data());
    _exit(127);
  }
  ProcessResult r;
  const int64_t end = monotonic_us() + static_cast<int64_t>(timeout_s * 1e6);
  while (waitpid(pid, &r.status, WNOHANG) == 0) {
    if (monotonic_us() > end) {
      kill(pid, SIGKILL);
      waitpid(pid, &r.status, 0);
      break;
    }
    usleep(10000);
  }
  std::ifstream in(err_path);
  r.err.assign(std::istreambuf_iterator<char>(in), {});
  return r;
}

std::string write_file(const std::string& name, const std::string& text) {
  const std::string path = whiskeye::testing::scratch_file(name, ".yaml");
  std::ofstream(path) << text;
  return path;
}

int exit_code(const ProcessResult& r) { return WIFEXITED(r.status) ? WEXITSTATUS(r.status) : -1; }

}  // namespace

TEST(DaemonProcesses, HelpExitsZero) {
  EXPECT_EQ(exit_code(run({WHISKERD, "--help"})), 0);
  EXPECT_EQ(exit_code(run({CAMERAD, "--help"})), 0);
}

TEST(DaemonProcesses, BadConfigIsOneLineNamingTheKeyAndExitsNonZero) {
  const std::string bad = write_file("bad", "can:\n  rate_hz: 5000\n");
  const ProcessResult w = run({WHISKERD, "-c", bad});
  EXPECT_EQ(exit_code(w), 2);
  EXPECT_NE(w.err.find("whiskerd: bad config:"), std::string::npos) << w.err;
  EXPECT_NE(w.err.find("can.rate_hz"), std::string::npos) << w.err;
  const std::string bad_cam = write_file("bad_cam", "camera:\n  formats: [RGB3]\n");
  const ProcessResult c = run({CAMERAD, "-c", bad_cam});
  EXPECT_EQ(exit_code(c), 2);
  EXPECT_NE(c.err.find("camera.formats"), std::string::npos) << c.err;
  EXPECT_EQ(exit_code(run({WHISKERD, "-c", "/nonexistent/whiskerd.yaml"})), 2);
}

TEST(DaemonProcesses, WhiskerdWithoutTheCanInterfaceFailsWithAReason) {
  const ProcessResult r = run({WHISKERD, "--no-gpio", "-i", "nocan7"});
  EXPECT_EQ(exit_code(r), 1);
  EXPECT_NE(r.err.find("nocan7"), std::string::npos) << r.err;
}

TEST(DaemonProcesses, CameradWaitsForAMissingCameraReadyAndDegraded) {
  // A datagram socket standing in for systemd's notify socket.
  const std::string sock_path = whiskeye::testing::scratch_file("notify", ".sock");
  unlink(sock_path.c_str());
  const int fd = socket(AF_UNIX, SOCK_DGRAM | SOCK_CLOEXEC, 0);
  ASSERT_GE(fd, 0);
  sockaddr_un addr{};
  addr.sun_family = AF_UNIX;
  std::snprintf(addr.sun_path, sizeof(addr.sun_path), "%s", sock_path.c_str());
  ASSERT_EQ(bind(fd, reinterpret_cast<sockaddr*>(&addr), sizeof(addr)), 0);
  setenv("NOTIFY_SOCKET", sock_path.c_str(), 1);

  LcmBus bus;
  DecodeErrors errors;
  std::vector<driver_status_t> status;
  subscribe<driver_status_t>(bus, "DRIVER_STATUS", [&](const driver_status_t& m) { status.push_back(m); }, errors);

  const pid_t pid = fork();
  if (pid == 0) {
    execl(CAMERAD, CAMERAD, "-d", "/dev/video_missing_42", static_cast<char*>(nullptr));
    _exit(127);
  }
  unsetenv("NOTIFY_SOCKET");
  std::string notified;
  const int64_t end = monotonic_us() + 8000000;
  while (monotonic_us() < end && (status.size() < 2 || notified.find("READY=1") == std::string::npos)) {
    bus.handle_timeout(50);
    char buf[256];
    const ssize_t n = recv(fd, buf, sizeof(buf), MSG_DONTWAIT);
    if (n > 0) notified.append(buf, static_cast<std::size_t>(n));
  }
  kill(pid, SIGTERM);
  int st = 0;
  waitpid(pid, &st, 0);
  close(fd);
  EXPECT_NE(notified.find("READY=1"), std::string::npos);
  ASSERT_GE(status.size(), 2u);
  EXPECT_EQ(status.back().driver, "camerad");
  EXPECT_EQ(status.back().state, int8_t{driver_status_t::STATE_DEGRADED});
  EXPECT_NE(status.back().message.find("/dev/video_missing_42"), std::string::npos) << status.back().message;
  EXPECT_TRUE(WIFEXITED(st) && WEXITSTATUS(st) == 0) << "camerad must exit cleanly on SIGTERM";
}
