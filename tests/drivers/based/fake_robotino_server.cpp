// The fake Robotino REST server of the tests as a program, for scenarios that run based as a real
// service (tests/deploy/scenario_systemd_units.sh): serves 127.0.0.1:PORT until SIGINT/SIGTERM.
#include "fake_robotino.h"

#include <CLI/CLI.hpp>

#include <csignal>
#include <cstdio>
#include <thread>

namespace {
volatile std::sig_atomic_t g_stop = 0;
void on_signal(int) { g_stop = 1; }
}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"fake Robotino REST server (tests): GET /data/odometry, POST /data/omnidrive on 127.0.0.1"};
  int port = 0;
  app.add_option("--port", port, "TCP port (0: any free one)")->check(CLI::Range(0, 65535));
  CLI11_PARSE(app, argc, argv);
  std::signal(SIGINT, on_signal);
  std::signal(SIGTERM, on_signal);
  whiskeye::based::testing::FakeRobotino base(port);
  std::printf("fake-robotino: serving %s\n", base.url().c_str());
  std::fflush(stdout);
  while (g_stop == 0) std::this_thread::sleep_for(std::chrono::milliseconds(50));
  std::printf("fake-robotino: %lld odometry requests, %zu commands\n", static_cast<long long>(base.odometry_requests()),
              base.commands().size());
  return 0;
}
