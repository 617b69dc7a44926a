// Burst-limited fault logging and the STARTING/OK/DEGRADED/FAULT state of the driver.
#include "whiskeye/based/health.h"

#include <cstdio>

namespace whiskeye::based {

std::string BurstLog::fault(const std::string& kind, const std::string& detail, int64_t now_us) {
  auto it = open_.find(kind);
  if (it != open_.end() && now_us - it->second.last_us <= quiet_us_) {
    ++it->second.count;
    it->second.last_us = now_us;
    return {};
  }
  open_[kind] = Burst{1, now_us};
  return kind + ": " + detail + " (repeats are counted, not logged, until quiet)";
}

std::vector<std::string> BurstLog::flush(int64_t now_us) {
  std::vector<std::string> lines;
  for (auto it = open_.begin(); it != open_.end();) {
    if (now_us - it->second.last_us > quiet_us_) {
      if (it->second.count > 1) {
        lines.push_back(it->first + ": burst over, " + std::to_string(it->second.count) + " in total");
      }
      it = open_.erase(it);
    } else {
      ++it;
    }
  }
  return lines;
}

const char* to_string(HealthState state) {
  switch (state) {
    case HealthState::kStarting: return "STARTING";
    case HealthState::kOk: return "OK";
    case HealthState::kDegraded: return "DEGRADED";
    case HealthState::kFault: return "FAULT";
  }
  return "?";
}

Health::Health(const ConnectionParams& connection, const OdometryParams& odometry, int64_t start_us)
    : fault_after_us_(seconds_to_utime(connection.fault_after_s)),
      degraded_hold_us_(seconds_to_utime(connection.degraded_hold_s)),
      stale_after_us_(seconds_to_utime(odometry.stale_after_s)),
      start_us_(start_us) {}

void Health::new_sample(int64_t now_us) { last_sample_us_ = now_us; }

void Health::fault(const std::string& message, int64_t now_us) {
  last_fault_us_ = now_us;
  last_fault_ = message;
}

void Health::reachable(bool yes, const std::string& message, int64_t now_us) {
  reachable_ = yes;
  if (!yes) {
    unreachable_message_ = message;
    fault(message, now_us);
  }
}

Health::Report Health::report(int64_t now_us) const {
  const auto seconds = [](int64_t us) {
    char buf[32];
    std::snprintf(buf, sizeof buf, "%.1f s", static_cast<double>(us) * 1e-6);
    return std::string(buf);
  };
  const std::string why = !reachable_ ? unreachable_message_ : last_fault_;
  const std::string suffix = why.empty() ? "" : " (last fault: " + why + ")";
  if (last_sample_us_ < 0) {
    if (now_us - start_us_ > fault_after_us_) {
      return {HealthState::kFault, "no valid odometry since start " + seconds(now_us - start_us_) + " ago" + suffix};
    }
    return {HealthState::kStarting, "waiting for the first odometry sample" + suffix};
  }
  const int64_t age = now_us - last_sample_us_;
  if (age > fault_after_us_) {
    return {HealthState::kFault, "no new odometry for " + seconds(age) + suffix};
  }
  if (!reachable_) return {HealthState::kDegraded, "base unreachable: " + unreachable_message_};
  if (age > stale_after_us_) {
    return {HealthState::kDegraded, "odometry stale: no new seq for " + seconds(age) + suffix};
  }
  if (last_fault_us_ >= 0 && now_us - last_fault_us_ <= degraded_hold_us_) {
    return {HealthState::kDegraded, last_fault_};
  }
  return {HealthState::kOk, ""};
}

}  // namespace whiskeye::based
