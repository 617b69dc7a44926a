// Driver health for DRIVER_STATUS and logging that does not flood: pure, time is an argument.
//   BurstLog: logs the first fault of a kind, stays quiet while that fault keeps recurring, and
//             reports how many there were once the burst has been quiet for a while.
//   Health:   STARTING / OK / DEGRADED / FAULT with a message, from the times of the last good
//             sample, the last fault and whether the base is reachable.
#pragma once

#include "whiskeye/based/params.h"
#include "whiskeye/common/utime.h"

#include <cstdint>
#include <map>
#include <string>
#include <vector>

namespace whiskeye::based {

class BurstLog {
 public:
  explicit BurstLog(double quiet_s) : quiet_us_(seconds_to_utime(quiet_s)) {}

  // A fault of `kind` at `now_us`. Returns the line to log (empty while a burst is going on).
  std::string fault(const std::string& kind, const std::string& detail, int64_t now_us);
  // Lines for the bursts that have been quiet for quiet_s by `now_us` (and closes them).
  std::vector<std::string> flush(int64_t now_us);

 private:
  struct Burst {
    int64_t count = 0;
    int64_t last_us = 0;
  };
  int64_t quiet_us_;
  std::map<std::string, Burst> open_;
};

enum class HealthState { kStarting = 0, kOk = 1, kDegraded = 2, kFault = 3 };  // = driver_status_t

const char* to_string(HealthState state);

class Health {
 public:
  Health(const ConnectionParams& connection, const OdometryParams& odometry, int64_t start_us);

  void new_sample(int64_t now_us);                          // a valid sample with a new seq
  void fault(const std::string& message, int64_t now_us);   // any counted fault
  void reachable(bool yes, const std::string& message, int64_t now_us);  // connect outcome

  struct Report {
    HealthState state = HealthState::kStarting;
    std::string message;
  };
  Report report(int64_t now_us) const;

 private:
  int64_t fault_after_us_;
  int64_t degraded_hold_us_;
  int64_t stale_after_us_;
  int64_t start_us_;
  int64_t last_sample_us_ = -1;
  int64_t last_fault_us_ = -1;
  std::string last_fault_;
  bool reachable_ = true;
  std::string unreachable_message_;
};

}  // namespace whiskeye::based
