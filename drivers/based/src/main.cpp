// based: Festo Robotino base over its REST API → ODOMETRY; BASE_CMD → motion; DRIVER_STATUS at 1 Hz.
// `based --circle R --speed V [--laps N]` drives the paper's experiment instead of following BASE_CMD.
#include "whiskeye/based/node.h"
#include "whiskeye/common/cli.h"
#include "whiskeye/common/clock.h"
#include "whiskeye/common/log.h"
#include "whiskeye/common/service.h"

#include <CLI/CLI.hpp>

#include <csignal>
#include <cstdio>
#include <functional>
#include <optional>
#include <vector>

namespace {

volatile std::sig_atomic_t g_signal = 0;
void on_signal(int sig) { g_signal = sig; }

// The daemon, until a signal or the last lap: 0, or 1 on a runtime failure.
int run(const whiskeye::based::BasedParams& params, const std::string& lcm_url,
        const std::optional<whiskeye::based::CircleSpec>& circle) {
  using namespace whiskeye;
  try {
    ServiceNotifier service("based", monotonic_us());
    LcmBus bus(lcm_url);
    based::BasedNode node(bus, params);
    if (circle) {
      node.drive_circle(*circle);
      std::fprintf(stderr, "based: %s\n", based::CircleTrajectory(*circle, params.command).describe().c_str());
    }
    // Worker threads inherit a mask with the signals blocked, so only this thread handles them.
    sigset_t set;
    sigemptyset(&set);
    sigaddset(&set, SIGINT);
    sigaddset(&set, SIGTERM);
    pthread_sigmask(SIG_BLOCK, &set, nullptr);
    std::fprintf(stderr, "based: base %s, odometry %.0f Hz, commands %.0f Hz, deadman %.2f s%s\n",
                 params.url.c_str(), params.odometry.poll_rate_hz, params.command.rate_hz,
                 params.command.deadman_s, circle ? ", driving a circle" : ", following BASE_CMD");
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
    log_error(std::string("based: ") + e.what());
    return 1;
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  using namespace whiskeye;
  cli::Program program("based",
                       "based: Festo Robotino base over its REST API (ODOMETRY out, BASE_CMD in, DRIVER_STATUS)");
  CLI::App& app = program.app();
  std::string url;
  std::string config;
  std::string lcm_url;
  double radius = 0.0;
  double speed = 0.0;
  int laps = 0;
  bool print_config = false;
  app.add_option("--url", url, "base REST server, http://host[:port], overrides url (default http://192.168.0.1:80)");
  program.add_config(config, "YAML parameters (see config/based.yaml)");
  program.add_lcm_url(lcm_url);
  auto* circle_opt = app.add_option("--circle", radius,
                                    "drive around a circle of this radius (m) facing outwards, instead of following BASE_CMD");
  auto* speed_opt = app.add_option("--speed", speed, "tangential speed on the circle, m/s (negative: clockwise)");
  auto* laps_opt = app.add_option("--laps", laps, "stop and exit after this many laps (default: until signalled)")
                       ->check(CLI::PositiveNumber);
  speed_opt->needs(circle_opt);
  circle_opt->needs(speed_opt);
  laps_opt->needs(circle_opt);
  program.add_print_config(print_config);
  app.add_flag("--print-params", print_config)->group("");  // its name before --print-config, kept working
  return program.run(argc, argv, [&] {
    std::vector<cli::Override> overrides;
    if (!url.empty()) overrides.push_back({"url", url, "--url"});
    const ParamNode node = cli::read_config(config, overrides);
    based::BasedParams params;
    based::load(node, params);  // a ParamError: exit 2
    if (program.print_config(node.dump())) return 0;
    std::optional<based::CircleSpec> circle;
    if (*circle_opt) {
      circle = based::CircleSpec{radius, speed, laps};
      try {
        based::CircleTrajectory check(*circle, params.command);  // a circle the limits allow
      } catch (const std::invalid_argument& e) {
        throw cli::UsageError(e.what());
      }
    }
    return run(params, lcm_url, circle);
  });
}
