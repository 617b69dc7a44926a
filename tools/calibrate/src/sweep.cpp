// whiskeye-calibrate theta on the live bus: whiskerd's own control loop (ControlLoop: the real-time
// thread, WhiskerCore's safety state machine, the motor lines' LineGuard) whisks slowly through the
// whole joint range, commanded 20 deg past each end stop, while a second socket records the bus. Any state but
// running before the sweep's end (a motor fault or e-stop on the lines, a silent board, a stale bus)
// aborts it: the control loop retracts and drops the enable line as whiskerd would.
#include "whiskeye/calibrate/sweep.h"

#include <whiskeye/common/clock.h>
#include <whiskeye/common/service.h>

#include <atomic>
#include <chrono>
#include <iostream>
#include <memory>
#include <thread>

#include "whiskeye/whiskerd/control_loop.h"

namespace whiskeye::calibrate {

SweepOutcome run_sweep(const whiskerd::Params& in_use, const SweepPlan& plan,
                       const std::function<void(const std::function<bool()>&)>& record) {
  whiskerd::Params p = in_use;
  // Commanded 20 deg past the stops: with θ gains 10 % off and offsets of 80 counts, still past them.
  const double over = plan.stop_rad + 20.0 * kPi / 180.0;
  p.controller.pattern.frequency_hz = plan.frequency_hz;
  p.controller.pattern.theta_min = -over;
  p.controller.pattern.theta_max = over;
  p.controller.pattern.theta_limit = over;
  p.controller.rcp.law = rcp::RcpLaw::Off;  // the pattern alone: contact must not cut the sweep short
  p.whisk_on_start = true;
  p.gpio = plan.gpio;
  p.lock_memory = false;
  p.status_period_s = 0.1;  // a fault is seen within 0.1 s
  if (!plan.interface.empty()) p.interface = plan.interface;

  std::unique_ptr<gpio::MotorLines> lines =
      p.gpio ? gpio::open_gpiod_lines(p.lines, "whiskeye-calibrate") : std::make_unique<gpio::NoMotorLines>();
  auto sock = std::make_unique<can::Socket>(p.interface);
  ServiceNotifier service("whiskeye-calibrate", monotonic_us());
  auto shared = std::make_unique<whiskerd::Shared>();
  std::atomic<bool> stop{false};
  std::atomic<bool> done{false};
  SweepOutcome outcome;
  bool started = false;

  std::thread control([&] {
    whiskerd::ControlLoop loop(p, std::move(sock), *lines, *shared, service, stop);
    loop.run();
    done = true;
  });
  // The control thread's reports: its log lines, and the safety state of every status.
  std::thread reports([&] {
    whiskerd::Item item;
    while (!(shared->rt_done.load() && shared->ring.size() == 0)) {
      if (!shared->ring.try_pop(item)) {
        std::this_thread::sleep_for(std::chrono::milliseconds(5));
        continue;
      }
      if (item.kind == whiskerd::Item::Kind::kLog) std::cerr << item.text.data() << "\n";  // "whiskerd: ..."
      if (item.kind != whiskerd::Item::Kind::kStatus) continue;
      const whiskerd::Safety s = item.status.safety;
      if (s == whiskerd::Safety::kRunning) started = true;
      if (!stop && outcome.abort.empty() && (s == whiskerd::Safety::kFault || (started && s != whiskerd::Safety::kRunning))) {
        outcome.abort = std::string("whiskerd's safety state machine went to ") + whiskerd::safety_name(s) + ": " +
                        item.status.reason;
        stop = true;
      }
    }
  });
  const auto until = std::chrono::steady_clock::now() + std::chrono::duration<double>(plan.seconds);
  record([&] { return stop.load() || done.load() || std::chrono::steady_clock::now() >= until; });
  stop = true;
  control.join();
  reports.join();
  if (!started && outcome.abort.empty()) outcome.abort = "whiskerd never started whisking (every board must stream)";
  if (shared->exit_code.load() != 0 && outcome.abort.empty()) outcome.abort = "whiskerd's control loop failed";
  return outcome;
}

}  // namespace whiskeye::calibrate
