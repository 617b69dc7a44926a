// sd_notify wrapper and the test-only stalls; see service.h.
#include "whiskeye/common/service.h"
#include "whiskeye/common/log.h"

#include <systemd/sd-daemon.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <stdexcept>
#include <thread>

namespace whiskeye {

FaultInjection parse_fault_injection(const std::string& spec) {
  FaultInjection f;
  if (spec.empty()) return f;
  const std::string main_loop = "stall-main-loop-after=";
  const std::string worker = "stall-worker-after=";
  const bool is_main = spec.compare(0, main_loop.size(), main_loop) == 0;
  const bool is_worker = spec.compare(0, worker.size(), worker) == 0;
  if (!is_main && !is_worker) {
    throw std::invalid_argument(std::string(kFaultInjectEnv) + "='" + spec + "': unknown fault (known: " + main_loop +
                                "<duration>, " + worker + "<duration>)");
  }
  const std::string value = spec.substr(is_main ? main_loop.size() : worker.size());
  std::size_t used = 0;
  double number = 0.0;
  try {
    number = std::stod(value, &used);
  } catch (const std::exception&) {
    used = 0;
  }
  const std::string unit = value.substr(used);
  double scale = 0.0;
  if (unit == "s") scale = 1e6;
  if (unit == "ms") scale = 1e3;
  if (used == 0 || scale == 0.0 || !(number >= 0.0) || number > 1e6) {
    throw std::invalid_argument(std::string(kFaultInjectEnv) + "='" + spec +
                                "': duration must be a non-negative number followed by s or ms");
  }
  (is_main ? f.stall_main_loop_after_us : f.stall_worker_after_us) = static_cast<int64_t>(number * scale);
  return f;
}

ServiceNotifier::ServiceNotifier(std::string daemon, int64_t start_mono_us)
    : daemon_(std::move(daemon)), start_us_(start_mono_us) {
  uint64_t usec = 0;
  if (sd_watchdog_enabled(0, &usec) > 0) keep_alive_us_ = static_cast<int64_t>(usec / 2);
  const char* spec = std::getenv(kFaultInjectEnv);
  faults_ = parse_fault_injection(spec ? spec : "");
  if (faults_.any()) {
    log_warning(daemon_ + ": TEST-ONLY fault injection active: " + kFaultInjectEnv + "=" + spec);
  }
}

void ServiceNotifier::ready(const std::string& status) {
  const std::string msg = status.empty() ? "READY=1" : "READY=1\nSTATUS=" + status;
  sd_notify(0, msg.c_str());
}

bool ServiceNotifier::keep_alive(int64_t now_mono_us) {
  if (keep_alive_us_ <= 0) return false;
  if (sent_any_ && now_mono_us - last_keep_alive_us_ < keep_alive_us_) return false;
  sd_notify(0, "WATCHDOG=1");
  last_keep_alive_us_ = now_mono_us;
  sent_any_ = true;
  return true;
}

void ServiceNotifier::stopping() { sd_notify(0, "STOPPING=1"); }

void ServiceNotifier::stall_if_injected(int64_t now_mono_us, const std::function<bool()>& stop) {
  stall_once(faults_.stall_main_loop_after_us, stalled_, now_mono_us,
             "main loop stalled (no more watchdog keep-alives)", stop);
}

void ServiceNotifier::stall_worker_if_injected(int64_t now_mono_us, const std::string& worker,
                                               const std::function<bool()>& stop) {
  stall_once(faults_.stall_worker_after_us, worker_stalled_, now_mono_us, worker + " stalled", stop);
}

void ServiceNotifier::stall_once(int64_t after_us, bool& stalled, int64_t now_mono_us, const std::string& what,
                                 const std::function<bool()>& stop) const {
  if (stalled || after_us < 0 || now_mono_us - start_us_ < after_us) return;
  stalled = true;  // once: after the stop request the loop runs on to shut down normally
  log_warning(daemon_ + ": fault injection: " + what);
  while (!stop()) std::this_thread::sleep_for(std::chrono::milliseconds(50));
}

}  // namespace whiskeye
