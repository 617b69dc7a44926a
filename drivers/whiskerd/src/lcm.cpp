// whiskerd's outputs as LCM messages (see lcm.h).
#include "whiskeye/whiskerd/lcm.h"

#include <string>
#include <utility>

namespace whiskeye::whiskerd {

static_assert(kStatusStale == whisker_sample_t::STATUS_STALE && kStatusSaturated == whisker_sample_t::STATUS_SATURATED &&
                  kStatusFault == whisker_sample_t::STATUS_FAULT && kStatusOvertemp == whisker_sample_t::STATUS_OVERTEMP,
              "the core's status bits are WHISKER_SAMPLE's");

void to_lcm(const PeriodOutput& in, whisker_sample_t& s, rcp_state_t& r) {
  rcp::fill_whisker_sample(in.utime, in.seq, in.theta, in.deflection_x, in.deflection_y, in.raw_x, in.raw_y,
                           in.raw_theta, in.status, s);
  rcp::fill_rcp_state(in.utime, in.cycle, in.phase, in.cycle_phase, in.enabled, in.contact, in.theta_ceiling,
                      in.theta_command, r);
}

void to_lcm(const StatusSnapshot& in, driver_status_t& out) {
  out.utime = in.utime;
  out.driver = "whiskerd";
  switch (in.safety) {
    case Safety::kWaiting: out.state = driver_status_t::STATE_STARTING; break;
    case Safety::kRunning: out.state = driver_status_t::STATE_OK; break;
    case Safety::kRetracting:
    case Safety::kDisabled:
    case Safety::kStopped: out.state = driver_status_t::STATE_DEGRADED; break;
    case Safety::kFault: out.state = driver_status_t::STATE_FAULT; break;
  }
  out.message = std::string(safety_name(in.safety)) + (in.reason[0] ? std::string(": ") + in.reason : "") +
                "; bus " + in.bus_state;
  if (in.safety == Safety::kRunning && std::string(in.bus_state) != "error-active") {
    out.state = driver_status_t::STATE_DEGRADED;
  }
  out.counter_names.assign(Counters::kNames, Counters::kNames + Counters::kCount);
  out.counter_values.assign(in.counters.begin(), in.counters.end());
  const std::pair<const char*, int64_t> can[] = {{"can_rx_frames", in.can_rx},
                                                 {"can_error_frames", in.can_error_frames},
                                                 {"can_bus_off", in.can_bus_off},
                                                 {"can_error_passive", in.can_error_passive},
                                                 {"can_reopens", in.can_reopens},
                                                 {"can_rx_overflow", in.can_rx_overflow}};
  for (const auto& [name, value] : can) {
    out.counter_names.push_back(name);
    out.counter_values.push_back(value);
  }
  out.num_counters = static_cast<int32_t>(out.counter_names.size());
  out.stat_names.clear();
  out.stat_values.clear();
  auto add = [&](const std::string& prefix, const LatencySummary& s) {
    out.stat_names.push_back(prefix + "_p50_us");
    out.stat_values.push_back(s.p50_us);
    out.stat_names.push_back(prefix + "_p99_us");
    out.stat_values.push_back(s.p99_us);
    out.stat_names.push_back(prefix + "_max_us");
    out.stat_values.push_back(s.max_us);
  };
  add("wake_latency", in.wake_latency);
  add("loop_time", in.loop_time);
  add("period_jitter", in.period_jitter);
  out.stat_names.push_back("rt_scheduling");
  out.stat_values.push_back(in.rt_scheduling ? 1.0 : 0.0);
  out.stat_names.push_back("periods");
  out.stat_values.push_back(static_cast<double>(in.loop_time.count));
  out.num_stats = static_cast<int32_t>(out.stat_names.size());
}

}  // namespace whiskeye::whiskerd
