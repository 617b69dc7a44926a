// whiskerd: the whisker head daemon. A real-time control thread (ControlLoop) runs at the sample
// rate: drain CAN frames -> WhiskerCore::step -> motor command on the bus -> the period's messages to
// the publisher thread (publish_loop), the only one that touches LCM and the one that reopens a CAN
// socket that went down (whiskeye/whiskerd/control_loop.h). This file opens the devices and wires
// the threads. SIGTERM / SIGINT retract the whiskers and drop the enable line.
#include <signal.h>

#include <CLI/CLI.hpp>
#include <atomic>
#include <iostream>
#include <memory>
#include <thread>
#include <vector>

#include <whiskeye/common/bus.h>
#include <whiskeye/common/cli.h>
#include <whiskeye/common/clock.h>
#include <whiskeye/common/log.h>
#include <whiskeye/common/service.h>

#include "whiskeye/can/can_socket.h"
#include "whiskeye/whiskerd/control_loop.h"
#include "whiskeye/whiskerd/config.h"

namespace {

using namespace whiskeye;
using namespace whiskeye::whiskerd;

std::atomic<bool> g_stop{false};
void on_signal(int) { g_stop.store(true); }

int run(const Params& params) {
  ServiceNotifier service("whiskerd", monotonic_us());  // a malformed WHISKEYE_FAULT_INJECT: exit 1
  std::unique_ptr<can::Socket> sock;
  std::unique_ptr<gpio::MotorLines> lines;
  std::unique_ptr<LcmBus> bus;
  try {
    sock = std::make_unique<can::Socket>(params.interface);
    // The 8-id blocks of samples and heartbeats (base .. base+7; load() rejects a base that is not a
    // multiple of 8): node ids 1..6 plus neighbours, so a misconfigured board (an unknown id next
    // to ours) is counted rather than silently filtered.
    std::vector<can::Filter> filters;
    for (uint32_t base : {params.ids.sample_base, params.ids.heartbeat_base}) filters.push_back({base, 0x7f8});
    sock->set_filters(filters);
    // ~1 s of bus traffic: a stalled control thread loses no frames (they show as stale periods).
    sock->set_receive_buffer(4 << 20);
    if (params.gpio) {
      lines = gpio::open_gpiod_lines(params.lines, "whiskerd");
    } else {
      lines = std::make_unique<gpio::NoMotorLines>();
    }
    bus = std::make_unique<LcmBus>(params.lcm_url);
  } catch (const std::exception& e) {
    log_error(std::string("whiskerd: ") + e.what());
    return 1;
  }
  std::cerr << "whiskerd: " << params.interface << " (" << (params.mode == wp::BusMode::kFd ? "CAN FD" : "classic CAN")
            << ", " << params.rate_hz << " Hz), " << lines->describe() << "\n";

  struct sigaction sa {};
  sa.sa_handler = on_signal;
  sigaction(SIGTERM, &sa, nullptr);
  sigaction(SIGINT, &sa, nullptr);

  auto shared = std::make_unique<Shared>();
  std::thread control([&] {
    ControlLoop loop(params, std::move(sock), *lines, *shared, service, g_stop);  // on the control thread
    loop.run();
  });
  std::thread publisher([&] { publish_loop(params, *bus, *shared, service); });
  service.ready();
  control.join();
  publisher.join();
  service.stopping();
  std::cerr << "whiskerd: stopped, motors disabled\n";
  return shared->exit_code.load();
}

}  // namespace

int main(int argc, char** argv) {
  cli::Program program("whiskerd",
                       "whiskerd: whisker sensors and motors over SocketCAN, RCP whisking control loop, LCM publisher");
  CLI::App& app = program.app();
  std::string config_path;
  std::string interface;
  std::string lcm_url;
  bool no_gpio = false;
  bool print_config = false;
  program.add_config(config_path, "whiskerd YAML (config/whiskerd.yaml), then the calibration drop-ins whiskerd.d/*.yaml beside it; defaults without it");
  app.add_option("-i,--interface", interface, "CAN interface, overrides can.interface");
  app.add_flag("--no-gpio", no_gpio,
               "run without motor enable / fault lines (rigs without GPIO), overrides gpio.enabled");
  program.add_lcm_url(lcm_url)->description("LCM URL, overrides lcm.url (default: $LCM_DEFAULT_URL, or LCM's default)");
  program.add_print_config(print_config);
  return program.run(argc, argv, [&] {
    // The file, then the command line's overrides: what is printed is what runs.
    std::vector<cli::Override> overrides;
    if (!interface.empty()) overrides.push_back({"can.interface", interface, "--interface"});
    if (no_gpio) overrides.push_back({"gpio.enabled", "false", "--no-gpio"});
    if (!lcm_url.empty()) overrides.push_back({"lcm.url", lcm_url, "--lcm-url"});
    const ParamNode root = cli::read_config(config_path, overrides);
    Params params;
    // Then the calibration drop-ins (whiskerd.d/*.yaml beside the file); a ParamError: exit 2.
    const std::string printed = load_with_dropins(root, config_path, params);
    if (program.print_config(printed)) return 0;
    std::cerr << printed;
    return run(params);
  });
}
