// The systemd service protocol shared by the daemons (whiskerd, camerad, based, slamd): READY=1 once
// the main loop runs, WATCHDOG=1 keep-alives from that loop, STOPPING=1 on the way out (all no-ops
// when not started by systemd), and a TEST-ONLY fault injection that stalls the main loop or a worker
// thread so tests can prove the keep-alives stop when either is stuck (docs/deployment.md, "Watchdog").
#pragma once

#include <cstdint>
#include <functional>
#include <string>

namespace whiskeye {

// Environment variable holding the fault-injection spec. Unset or empty: off (always in production).
inline constexpr const char* kFaultInjectEnv = "WHISKEYE_FAULT_INJECT";

struct FaultInjection {
  // The main loop blocks once this long has passed since the daemon started; < 0: never.
  int64_t stall_main_loop_after_us = -1;
  // A worker thread blocks once this long has passed since the daemon started; < 0: never. Only a
  // daemon with worker threads outside its main loop acts on it (based: its odometry thread).
  int64_t stall_worker_after_us = -1;
  bool any() const { return stall_main_loop_after_us >= 0 || stall_worker_after_us >= 0; }
};

// Parses the spec: "" (off), "stall-main-loop-after=<number><s|ms>" (e.g. "stall-main-loop-after=2s")
// or "stall-worker-after=<number><s|ms>". Throws std::invalid_argument naming what was wrong, so a
// typo cannot silently disable a test.
FaultInjection parse_fault_injection(const std::string& spec);

class ServiceNotifier {
 public:
  // Reads $WATCHDOG_USEC (through sd_watchdog_enabled) and $WHISKEYE_FAULT_INJECT; start_mono_us is
  // the daemon's start on the monotonic clock. Throws std::invalid_argument on a malformed spec.
  ServiceNotifier(std::string daemon, int64_t start_mono_us);

  bool watchdog_enabled() const { return keep_alive_us_ > 0; }
  // Half of WATCHDOG_USEC (systemd's recommendation), 0 without a watchdog.
  int64_t keep_alive_interval_us() const { return keep_alive_us_; }
  const FaultInjection& fault_injection() const { return faults_; }

  void ready(const std::string& status = "");
  // Sends WATCHDOG=1 if a keep-alive interval has passed since the last one. Call it from the loop
  // whose progress it vouches for, at least once per interval; returns true when it sent one.
  bool keep_alive(int64_t now_mono_us);
  void stopping();

  // TEST-ONLY (WHISKEYE_FAULT_INJECT=stall-main-loop-after=T): once T has passed since start, logs once
  // and blocks the calling loop, polling `stop` every 50 ms, until it returns true; then returns so
  // the daemon can shut down normally. Without the variable it returns at once.
  void stall_if_injected(int64_t now_mono_us, const std::function<bool()>& stop);
  // TEST-ONLY (WHISKEYE_FAULT_INJECT=stall-worker-after=T): the same for one worker thread, named in
  // the log line as `worker` ("<daemon>: fault injection: <worker> stalled"). Call it from that
  // worker's loop only; it touches nothing the main loop's calls use.
  void stall_worker_if_injected(int64_t now_mono_us, const std::string& worker, const std::function<bool()>& stop);

 private:
  // Once `after_us` (≥ 0) has passed since start: logs "<daemon>: fault injection: <what>" and blocks
  // until stop() (polled every 50 ms). `stalled` makes it happen once.
  void stall_once(int64_t after_us, bool& stalled, int64_t now_mono_us, const std::string& what,
                  const std::function<bool()>& stop) const;

  std::string daemon_;
  int64_t start_us_;
  int64_t keep_alive_us_ = 0;
  int64_t last_keep_alive_us_ = 0;
  bool sent_any_ = false;
  FaultInjection faults_;
  bool stalled_ = false;         // the main loop's stall happened
  bool worker_stalled_ = false;  // the worker's stall happened (touched by that worker only)
};

}  // namespace whiskeye
