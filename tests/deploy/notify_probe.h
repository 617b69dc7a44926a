// Stands in for systemd's side of the sd_notify protocol in tests: a unix datagram socket the test
// owns (NOTIFY_SOCKET), every message received timestamped, and the check that a daemon started with
// WATCHDOG_USEC sends READY=1, then WATCHDOG=1 about every WATCHDOG_USEC/2, and stops sending once its
// main loop or a worker thread is stalled by the test-only fault injection (docs/deployment.md, "Watchdog").
#pragma once

#include <atomic>
#include <cstdint>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

namespace whiskeye::deploy_testing {

class NotifyListener {
 public:
  struct Message {
    int64_t mono_us;
    std::string text;  // one assignment, e.g. "WATCHDOG=1"
  };
  // Binds a fresh socket under /tmp (unix socket paths are limited to 107 bytes).
  NotifyListener();
  ~NotifyListener();
  NotifyListener(const NotifyListener&) = delete;
  NotifyListener& operator=(const NotifyListener&) = delete;

  const std::string& path() const { return path_; }
  std::vector<Message> messages() const;
  // Receive times of messages equal to `text`.
  std::vector<int64_t> times_of(const std::string& text) const;

 private:
  void run();
  std::string path_;
  int fd_ = -1;
  std::atomic<bool> stop_{false};
  mutable std::mutex mutex_;
  std::vector<Message> messages_;
  std::thread thread_;
};

struct WatchdogCheck {
  int64_t watchdog_usec = 400000;
  std::string fault = "stall-main-loop-after";          // WHISKEYE_FAULT_INJECT=<fault>=<stall_after_s>s
  std::string stall_log = "fault injection: main loop stalled";  // what the daemon logs when it stalls
  double stall_grace_s = 0.0;   // keep-alives allowed this long after stall_log (a worker's limit)
  double stall_after_s = 4.0;
  double ready_timeout_s = 15.0;
  double window_s = 1.6;        // regular keep-alives are measured over this window after READY=1
  double max_gap_factor = 1.5;  // largest gap allowed in the window, in WATCHDOG_USEC (1.0 = systemd's limit)
};

struct WatchdogReport {
  bool ready = false;
  double ready_after_s = 0;
  int pings_in_window = 0;
  double max_gap_s = 0;
  bool stall_logged = false;
  double quiet_s = 0;           // observed time without keep-alives after the stall
  int pings_after_stall = 0;
  bool alive_while_stalled = false;
  int exit_code = -1;           // after SIGINT once stalled
  bool stopping_sent = false;
  std::string output;           // the daemon's stdout+stderr
  std::vector<std::string> problems;  // empty: every property held
  std::string summary() const;
};

// Starts argv with NOTIFY_SOCKET, WATCHDOG_USEC and the stall injected, watches the notifications,
// then interrupts the stalled daemon. extra_env: more "K=V" for the daemon.
WatchdogReport check_watchdog(const std::vector<std::string>& argv, const WatchdogCheck& check,
                              const std::vector<std::string>& extra_env = {});

}  // namespace whiskeye::deploy_testing
