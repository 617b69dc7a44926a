// camerad: V4L2 camera -> CAMERA (image_t, the pixels as captured) and DRIVER_STATUS at 1 Hz.
// The device disappearing (unplugged, driver reloaded: ENODEV / EIO) is not fatal: camerad closes it
// and reopens with exponential backoff, reporting DEGRADED meanwhile. Bad configuration is the only
// startup failure. The states live in CameraNode (whiskeye/camerad/camera_node.h); this file wires
// it to LCM, systemd and the signals.
#include <signal.h>

#include <CLI/CLI.hpp>
#include <atomic>
#include <iostream>
#include <memory>
#include <vector>

#include <whiskeye/common/bus.h>
#include <whiskeye/common/channels.h>
#include <whiskeye/common/cli.h>
#include <whiskeye/common/clock.h>
#include <whiskeye/common/log.h>
#include <whiskeye/common/params.h>
#include <whiskeye/common/service.h>

#include "whiskeye/camerad/camera_node.h"

namespace {

using namespace whiskeye;

std::atomic<bool> g_stop{false};
void on_signal(int) { g_stop.store(true); }

int run(const camerad::Params& p) {
  ServiceNotifier service("camerad", monotonic_us());  // a malformed WHISKEYE_FAULT_INJECT: exit 1
  std::unique_ptr<LcmBus> bus;
  try {
    bus = std::make_unique<LcmBus>(p.lcm_url);
  } catch (const std::exception& e) {
    log_error(std::string("camerad: ") + e.what());
    return 1;
  }
  struct sigaction sa {};
  sa.sa_handler = on_signal;
  sigaction(SIGTERM, &sa, nullptr);
  sigaction(SIGINT, &sa, nullptr);

  // What the V4L2 driver refuses (a size, a rate) is a warning.
  auto driver_log = [](const std::string& line) { log_warning(line); };
  auto log = [](LogLevel level, const std::string& line) { log_line(level, line); };
  camerad::CameraNode node(*bus, p, camerad::v4l2_factory(driver_log), camerad::system_clock(), log);
  node.set_ready_hook([&service] { service.ready(); });
  while (!g_stop.load()) {
    const int64_t t = node.step();
    service.keep_alive(t);
    // Test-only (WHISKEYE_FAULT_INJECT): a stuck capture loop, to prove the watchdog notices.
    service.stall_if_injected(t, [] { return g_stop.load(); });
  }
  service.stopping();
  std::cerr << "camerad: stopped after " << node.frames() << " frames\n";
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  cli::Program program("camerad", "camerad: V4L2 camera capture (mmap streaming) published as CAMERA over LCM");
  CLI::App& app = program.app();
  std::string config_path, device, lcm_url;
  bool print_config = false;
  program.add_config(config_path, "camerad YAML (config/camerad.yaml); defaults without it");
  app.add_option("-d,--device", device, "video device, overrides camera.device (and clears camera.match_card)");
  program.add_lcm_url(lcm_url)->description("LCM URL, overrides lcm.url (default: $LCM_DEFAULT_URL, or LCM's default)");
  program.add_print_config(print_config);
  return program.run(argc, argv, [&] {
    std::vector<cli::Override> overrides;
    if (!device.empty()) {
      overrides.push_back({"camera.device", device, "--device"});
      overrides.push_back({"camera.match_card", "", "--device"});
    }
    if (!lcm_url.empty()) overrides.push_back({"lcm.url", lcm_url, "--lcm-url"});
    const ParamNode root = cli::read_config(config_path, overrides);
    camerad::Params p;
    camerad::load(root, p);  // a ParamError: exit 2
    if (program.print_config(root.dump())) return 0;
    std::cerr << root.dump();
    return run(p);
  });
}
