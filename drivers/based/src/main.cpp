// based: Festo Robotino base over its REST API → ODOMETRY; BASE_CMD → motion; DRIVER_STATUS at 1 Hz.
// `based --circle R --speed V [--laps N]` drives the paper's experiment instead of following BASE_CMD.
#include "whiskeye/based/node.h"
#include "whiskeye/common/clock.h"
#include "whiskeye/common/service.h"

#include <CLI/CLI.hpp>

#include <csignal>
#include <cstdio>
#include <functional>
#include <iostream>

namespace {

volatile std::sig_atomic_t g_signal = 0;
void on_signal(int sig) { g_signal = sig; }

}  // namespace

int main(int argc, char** argv) {
  using namespace whiskeye;
  CLI::App app{"based: Festo Robotino base over its REST API (ODOMETRY out, BASE_CMD in, DRIVER_STATUS)"};
  std::string url;
  std::string config;
  std::string lcm_url;
  double radius = 0.0;
  double speed = 0.0;
  int laps = 0;
  bool print_params = false;
  app.add_option("--url", url, "base REST server, http://host[:port] (default from config: http://192.168.0.1:80)");
  app.add_option("--config", config, "YAML parameters (see config/based.yaml)")->check(CLI::ExistingFile);
  app.add_option("--lcm-url", lcm_url, "LCM URL (default: $LCM_DEFAULT_URL or LCM's default)");
  auto* circle_opt = app.add_option("--circle", radius,
                                    "drive around a circle of this radius (m) facing outwards, instead of following BASE_CMD");
  auto* speed_opt = app.add_option("--speed", speed, "tangential speed on the circle, m/s (negative: clockwise)");
  auto* laps_opt = app.add_option("--laps", laps, "stop and exit after this many laps (default: until signalled)")
                       ->check(CLI::PositiveNumber);
  speed_opt->needs(circle_opt);
  circle_opt->needs(speed_opt);
  laps_opt->needs(circle_opt);
  app.add_flag("--print-params", print_params, "print every parameter with its value and exit");
  CLI11_PARSE(app, argc, argv);

  based::BasedParams params;
  try {
    const ParamNode node = config.empty() ? ParamNode::empty() : ParamNode::from_file(config);
    based::load(node, params);
    if (!url.empty()) {
      based::check_url(url, "--url");
      params.url = url;
    }
    if (print_params) {
      std::cout << node.dump();
      return 0;
    }
  } catch (const ParamError& e) {
    std::cerr << "based: " << e.what() << "\n";
    return 2;
  }

  try {
    ServiceNotifier service("based", monotonic_us());
    LcmBus bus(lcm_url);
    based::BasedNode node(bus, params);
    if (*circle_opt) {
      node.drive_circle(based::CircleSpec{radius, speed, laps});
      std::fprintf(stderr, "based: %s\n", based::CircleTrajectory(based::CircleSpec{radius, speed, laps}, params.command).describe().c_str());
    }
    // Worker threads inherit a mask with the signals blocked, so only this thread handles them.
    sigset_t set;
    sigemptyset(&set);
    sigaddset(&set, SIGINT);
    sigaddset(&set, SIGTERM);
    pthread_sigmask(SIG_BLOCK, &set, nullptr);
    std::fprintf(stderr, "based: base %s, odometry %.0f Hz, commands %.0f Hz, deadman %.2f s%s\n",
                 params.url.c_str(), params.odometry.poll_rate_hz, params.command.rate_hz,
                 params.command.deadman_s, *circle_opt ? ", driving a circle" : ", following BASE_CMD");
    if (service.fault_injection().stall_worker_after_us >= 0) {
      node.set_poll_hook([&service](const std::function<bool()>& stopping) {
        service.stall_worker_if_injected(monotonic_us(), "odometry thread", stopping);
      });
    }
    node.start();
    struct sigaction sa {};
    sa.sa_handler = on_signal;
    sigemptyset(&sa.sa_mask);
    sigaction(SIGINT, &sa, nullptr);
    sigaction(SIGTERM, &sa, nullptr);
    pthread_sigmask(SIG_UNBLOCK, &set, nullptr);

    service.ready();
    while (g_signal == 0 && !node.finished()) {
      bus.handle_timeout(100);
      const int64_t now = monotonic_us();
      // Sent when due (the loop wakes at least every 100 ms), and only while the odometry, command
      // and status threads all run: the main loop alone vouches for none of the base's I/O.
      if (node.check_workers(now).empty()) service.keep_alive(now);
      // Test-only (WHISKEYE_FAULT_INJECT): a stuck main loop, to prove the watchdog notices.
      service.stall_if_injected(now, [] { return g_signal != 0; });
    }
    service.stopping();
    if (g_signal != 0) std::fprintf(stderr, "based: signal %d, stopping the base\n", static_cast<int>(g_signal));
    node.stop();
    std::fprintf(stderr, "based: stopped\n");
  } catch (const std::exception& e) {
    std::cerr << "based: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
