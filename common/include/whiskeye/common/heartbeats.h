// Liveness of a daemon's worker threads, for the loop that sends the systemd watchdog keep-alive.
// Each worker beats once per iteration of its loop; the keep-alive loop asks stalled() and withholds
// WATCHDOG=1 while a worker has been silent for longer than its limit, so systemd restarts a daemon
// whose worker hangs even though its main loop still turns (docs/deployment.md, "Watchdog").
// Times are passed in (monotonic µs), so the logic is testable without clocks.
#pragma once

#include <atomic>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

namespace whiskeye {

class WorkerHeartbeats {
 public:
  // Registers a worker that must beat at least every limit_us; it counts as having beaten at now_us.
  // Returns its index for beat(). Call before the workers start (not thread-safe).
  int add(std::string name, int64_t limit_us, int64_t now_us);
  // From the worker's own thread; thread-safe.
  void beat(int index, int64_t now_us);
  // The first worker silent for longer than its limit, described as
  // "<name> thread silent for 3.20 s (limit 2.50 s)"; empty when every worker is alive. Thread-safe.
  std::string stalled(int64_t now_us) const;

 private:
  struct Worker {
    std::string name;
    int64_t limit_us;
    std::atomic<int64_t> last_us;
  };
  std::vector<std::unique_ptr<Worker>> workers_;
};

}  // namespace whiskeye
