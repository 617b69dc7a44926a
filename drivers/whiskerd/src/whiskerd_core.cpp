// whiskerd's control core (see whiskerd_core.h).
#include "whiskeye/whiskerd/whiskerd_core.h"

#include <whiskeye/driver_status_t.hpp>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <utility>

namespace whiskeye::whiskerd {

const char* const Counters::kNames[Counters::kCount] = {
    "frames", "samples", "heartbeats", "rejected_unknown_id", "rejected_wrong_length",
    "rejected_out_of_range", "rejected_wrong_frame_type", "gaps", "incomplete_samples",
    "stale_board_periods", "deadline_misses", "publish_drops", "can_tx_errors", "late_samples",
    "board_resyncs", "overtemp_board_periods", "gaps_board0", "gaps_board1", "gaps_board2", "gaps_board3", "gaps_board4", "gaps_board5"};

const char* safety_name(Safety s) {
  switch (s) {
    case Safety::kWaiting: return "waiting";
    case Safety::kRunning: return "running";
    case Safety::kRetracting: return "retracting";
    case Safety::kDisabled: return "disabled";
    case Safety::kFault: return "fault";
    case Safety::kStopped: return "stopped";
  }
  return "?";
}

namespace {

// Reasons are static strings: the status snapshot carries the pointer to the publisher thread,
// which may outlive the core, and the real-time path never formats text.
constexpr const char* kBusStaleRetract = "stale bus: no samples from any board, retracting";
constexpr const char* kBusStaleDisabled = "stale bus: motors disabled until every board streams";
constexpr const char* kBoardSilentRetract[wp::kNumBoards] = {
    "board 0: no samples for can.stale_timeout_s, retracting",
    "board 1: no samples for can.stale_timeout_s, retracting",
    "board 2: no samples for can.stale_timeout_s, retracting",
    "board 3: no samples for can.stale_timeout_s, retracting",
    "board 4: no samples for can.stale_timeout_s, retracting",
    "board 5: no samples for can.stale_timeout_s, retracting"};
constexpr const char* kBoardSilentDisabled[wp::kNumBoards] = {
    "board 0: no samples, motors disabled until every board streams",
    "board 1: no samples, motors disabled until every board streams",
    "board 2: no samples, motors disabled until every board streams",
    "board 3: no samples, motors disabled until every board streams",
    "board 4: no samples, motors disabled until every board streams",
    "board 5: no samples, motors disabled until every board streams"};
static_assert(wp::kNumBoards == 6, "one reason string per board above");

// Moves every time of a whisk cycle by offset_us (monotonic -> epoch).
void shift_times(rcp::WhiskCycle& c, int64_t offset_us) {
  c.utime_start += offset_us;
  c.utime_end += offset_us;
  for (rcp::WhiskCycle::Sample& s : c.samples) s.utime += offset_us;
}

void load_calibration(const ParamNode& n, wp::WhiskerCalibration& c) {
  n.get("offset_x", c.offset_x, -4096.0, 4096.0);
  n.get("offset_y", c.offset_y, -4096.0, 4096.0);
  n.get("gain_x", c.gain_x, -1.0, 1.0);
  n.get("gain_y", c.gain_y, -1.0, 1.0);
  n.get("rotation", c.rotation, -7.0, 7.0);
  n.get("theta_offset", c.theta_offset, -1024.0, 1024.0);
  n.get("theta_gain", c.theta_gain, -0.01, 0.01);
  if (c.theta_gain == 0.0) throw ParamError(n.path_of("theta_gain") + " must not be 0");
}

}  // namespace

void load(const ParamNode& root, Params& p) {
  const ParamNode can = root.section("can");
  can.get("interface", p.interface);
  std::string mode = p.mode == wp::BusMode::kFd ? "fd" : "classic";
  can.get("mode", mode);
  if (mode == "fd") {
    p.mode = wp::BusMode::kFd;
  } else if (mode == "classic") {
    p.mode = wp::BusMode::kClassic;
  } else {
    throw ParamError(can.path_of("mode") + " = \"" + mode + "\" is not fd or classic");
  }
  if (p.mode == wp::BusMode::kClassic && !can.has("rate_hz")) p.rate_hz = 100.0;
  can.get("rate_hz", p.rate_hz, 10.0, 1000.0);
  if (p.mode == wp::BusMode::kClassic && p.rate_hz > 200.0) {
    throw ParamError(can.path_of("rate_hz") + " = " + std::to_string(p.rate_hz) +
                     " exceeds the classic-CAN bus capacity (max 200 Hz, see docs/can-protocol.md)");
  }
  can.get("stale_timeout_s", p.stale_timeout_s, 0.005, 10.0);
  const ParamNode ids = can.section("ids");
  int sample = static_cast<int>(p.ids.sample_base), command = static_cast<int>(p.ids.command_base),
      heartbeat = static_cast<int>(p.ids.heartbeat_base);
  ids.get("sample_base", sample, 0, 0x7ff - wp::kNumBoards);
  ids.get("command_base", command, 0, 0x7ff - wp::kNumBoards);
  ids.get("heartbeat_base", heartbeat, 0, 0x7ff - wp::kNumBoards);
  // whiskerd receives samples and heartbeats through kernel filters on the aligned 8-id block
  // (mask 0x7f8, see main.cpp, `run`): node ids 1..6 must fall in base's own block.
  static_assert(wp::kNumBoards < 8, "node ids 1..kNumBoards fit one block of 8 ids");
  for (const auto& [key, base] : {std::pair<const char*, int>{"sample_base", sample}, {"heartbeat_base", heartbeat}}) {
    if (base % 8 != 0) {
      char hex[8];
      std::snprintf(hex, sizeof hex, "0x%03x", base);
      throw ParamError(ids.source() + ": '" + ids.path_of(key) + "' = " + hex +
                       " must be a multiple of 8 (0x...0 or 0x...8): the CAN filter covers the aligned block "
                       "base..base+7");
    }
  }
  auto overlap = [](int a, int b) { return std::abs(a - b) <= wp::kNumBoards; };
  if (overlap(sample, command) || overlap(sample, heartbeat) || overlap(command, heartbeat)) {
    throw ParamError(ids.path_of("sample_base") + ", command_base, heartbeat_base: id ranges overlap");
  }
  p.ids = {static_cast<uint32_t>(sample), static_cast<uint32_t>(command), static_cast<uint32_t>(heartbeat)};

  const ParamNode safety = root.section("safety");
  safety.get("retract_time_s", p.retract_time_s, 0.0, 10.0);
  safety.get("whisk_on_start", p.whisk_on_start);

  const ParamNode cal = root.section("calibration");
  wp::WhiskerCalibration def;
  load_calibration(cal.section("default"), def);
  p.calibration.fill(def);
  for (const ParamNode& w : cal.list("whiskers")) {
    int index = -1;
    w.require("index", index);
    if (index < 0 || index >= kN) throw ParamError(w.path_of("index") + " must be 0..23");
    load_calibration(w, p.calibration[index]);
  }

  const ParamNode gpio = root.section("gpio");
  gpio.get("enabled", p.gpio);
  gpio.get("enable_line", p.lines.enable);
  gpio.get("fault_line", p.lines.fault);
  gpio.get("estop_line", p.lines.estop);
  gpio.get("fault_active_low", p.lines.fault_active_low);
  gpio.get("estop_active_low", p.lines.estop_active_low);

  const ParamNode rt = root.section("realtime");
  rt.get("priority", p.rt_priority, 1, 99);
  rt.get("cpu", p.rt_cpu, -1, 1023);
  rt.get("lock_memory", p.lock_memory);

  const ParamNode lcm = root.section("lcm");
  lcm.get("url", p.lcm_url);
  lcm.get("channel_sample", p.channel_sample);
  lcm.get("channel_state", p.channel_state);
  lcm.get("channel_cycle", p.channel_cycle);
  lcm.get("channel_status", p.channel_status);
  lcm.get("status_period_s", p.status_period_s, 0.1, 60.0);

  rcp::load(root.section("rcp"), p.controller);
  root.check_no_unknown_keys();
}

WhiskerCore::WhiskerCore(const CoreParams& params)
    : params_(params), controller_(params.controller, params.rate_hz), assembler_(params.mode) {
  last_sample_mono_.fill(-1);
  for (; pooled_cycles_ < 2; ++pooled_cycles_) cycle_pool_[pooled_cycles_] = std::make_unique<rcp::WhiskCycle>();
  for (int w = 0; w < kN; ++w) {
    cos_r_[w] = std::cos(params_.calibration[w].rotation);
    sin_r_[w] = std::sin(params_.calibration[w].rotation);
  }
}

const char* WhiskerCore::take_rejection_line() {
  if (!rejection_pending_) return nullptr;
  rejection_pending_ = false;
  return rejection_line_.data();
}

void WhiskerCore::on_frame(uint32_t id, bool fd, std::span<const uint8_t> data, int64_t mono_us) {
  ++counters_[Counters::kFrames];
  const wp::Decoded d = wp::decode_frame(id, fd, data, params_.mode, params_.ids);
  switch (d.kind) {
    case wp::FrameKind::kRejected:
      switch (d.reject) {
        case wp::Reject::kUnknownId: ++counters_[Counters::kRejectedUnknownId]; break;
        case wp::Reject::kWrongLength: ++counters_[Counters::kRejectedWrongLength]; break;
        case wp::Reject::kOutOfRange: ++counters_[Counters::kRejectedOutOfRange]; break;
        default: ++counters_[Counters::kRejectedWrongFrameType]; break;
      }
      if (++rejected_frames_ == next_rejection_to_log_) {
        wp::format_reject(d, rejection_line_);
        rejection_pending_ = true;
        next_rejection_to_log_ *= 10;
      }
      break;
    case wp::FrameKind::kSample:
      if (assembler_.add(d.sample)) {
        ++counters_[Counters::kSamples];
        last_sample_mono_[d.sample.board] = mono_us;
      }
      break;
    case wp::FrameKind::kFragment:
      if (assembler_.add(d.fragment)) {
        ++counters_[Counters::kSamples];
        last_sample_mono_[d.fragment.board] = mono_us;
      }
      break;
    case wp::FrameKind::kHeartbeat:
      ++counters_[Counters::kHeartbeats];
      // A board that rebooted starts its seq over: without this, the jump from its old seq was
      // counted as up to 32767 lost samples when that seq was in the upper half of the u16 space.
      if (d.heartbeat.state == wp::kNmtBootUp) assembler_.restart(d.heartbeat.board);
      break;
    case wp::FrameKind::kCommand:
      break;  // another host's command (or our own echo): not ours to act on
  }
  counters_[Counters::kGaps] = assembler_.total_gaps();
  counters_[Counters::kIncomplete] = assembler_.incomplete();
  counters_[Counters::kLateSamples] = assembler_.late();
  counters_[Counters::kBoardResyncs] = assembler_.resyncs();
  for (int b = 0; b < wp::kNumBoards; ++b) counters_[Counters::kGapsBoard0 + b] = assembler_.gaps(b);
}

bool WhiskerCore::timed_out(int64_t last_mono, int64_t mono_us) const {
  return last_mono < 0 || static_cast<double>(mono_us - last_mono) > params_.stale_timeout_s * 1e6;
}

bool WhiskerCore::bus_stale(int64_t mono_us) const {
  for (const int64_t last : last_sample_mono_) {
    if (!timed_out(last, mono_us)) return false;
  }
  return true;
}

int WhiskerCore::silent_board(int64_t mono_us) const {
  for (int b = 0; b < wp::kNumBoards; ++b) {
    if (timed_out(last_sample_mono_[b], mono_us)) return b;
  }
  return -1;
}

void WhiskerCore::fault() {
  if (safety_ == Safety::kStopped) return;
  safety_ = Safety::kFault;
  motors_enabled_ = false;
  controller_.disable();
  reason_ = "motor fault or emergency stop (latched until restart)";
}

void WhiskerCore::request_stop() { stop_requested_ = true; }

void WhiskerCore::start_retract(int64_t mono_us, const char* why) {
  safety_ = Safety::kRetracting;
  retract_start_mono_ = mono_us;
  controller_.disable();
  reason_ = why;
}

void WhiskerCore::recycle(std::unique_ptr<rcp::WhiskCycle> used) {
  if (!used) return;
  controller_.recycle(std::move(*used));
  if (pooled_cycles_ < kCyclePool) cycle_pool_[pooled_cycles_++] = std::move(used);
}

void WhiskerCore::step(int64_t utime, int64_t mono_us, PeriodOutput& out) {
  ++seq_;
  out.utime = utime;
  out.seq = seq_;
  recycle(std::move(out.completed_cycle));  // not handed on (e.g. the ring was full)
  out.completed_cycle.reset();

  // Latest sample of every board -> calibration -> controller input. The controller runs on the
  // monotonic clock: its dt, slew limit, ramps and cycle timing must not see wall-clock steps.
  rcp::WhiskerSample in;
  in.utime = mono_us;
  in.seq = seq_;
  bool all_fresh = true;
  for (int b = 0; b < wp::kNumBoards; ++b) {
    const bool have = assembler_.has_sample(b);
    const bool fresh = have && assembler_.samples(b) != used_samples_[b];
    used_samples_[b] = assembler_.samples(b);
    if (!fresh) {
      ++counters_[Counters::kStaleBoardPeriods];
      all_fresh = false;
    }
    const wp::BoardSample& s = assembler_.latest(b);
    // An over-temperature board has its motors taken out of the enable mask (its driver heats its
    // motors: driving them on would cook them) until it cools down; its Hall sensors still measure.
    const bool overtemp = have && (s.status & wp::kBoardOvertemp);
    if (fresh && overtemp) ++counters_[Counters::kOvertempBoardPeriods];
    for (int k = 0; k < wp::kWhiskersPerBoard; ++k) {
      const int w = b * wp::kWhiskersPerBoard + k;
      const wp::WhiskerRaw& raw = s.whiskers[k];
      int8_t status = 0;
      if (!fresh) status |= whisker_sample_t::STATUS_STALE;
      if (have && (std::abs(raw.x) >= wp::kHallLimit || std::abs(raw.y) >= wp::kHallLimit)) {
        status |= whisker_sample_t::STATUS_SATURATED;
      }
      const bool faulty = have && (raw.fault || (s.status & wp::kBoardFault));
      if (faulty) status |= whisker_sample_t::STATUS_FAULT;
      if (overtemp) status |= whisker_sample_t::STATUS_OVERTEMP;
      out.status[w] = status;
      out.raw_x[w] = raw.x;
      out.raw_y[w] = raw.y;
      out.raw_theta[w] = raw.theta;
      const wp::CalibratedWhisker c = wp::calibrate(raw, params_.calibration[w], cos_r_[w], sin_r_[w]);
      out.theta[w] = c.theta;
      out.deflection_x[w] = c.x;
      out.deflection_y[w] = c.y;
      in.theta[w] = c.theta;
      in.deflection_x[w] = c.x;
      in.deflection_y[w] = c.y;
      in.valid[w] = fresh && !faulty;
    }
  }

  // Safety state machine.
  const bool stale = bus_stale(mono_us);
  const int silent = silent_board(mono_us);
  switch (safety_) {
    case Safety::kWaiting:
      if (stop_requested_) {
        safety_ = Safety::kStopped;
      } else if (all_fresh && !stale) {
        safety_ = Safety::kRunning;
        motors_enabled_ = true;
        if (params_.whisk_on_start) controller_.enable();
        reason_ = "";
      }
      break;
    case Safety::kRunning:
      if (stop_requested_) {
        start_retract(mono_us, "stopping: retracting");
      } else if (stale) {
        start_retract(mono_us, kBusStaleRetract);
      } else if (silent >= 0) {
        start_retract(mono_us, kBoardSilentRetract[silent]);
      }
      break;
    case Safety::kRetracting:
      // The enable line drops once the whiskers are at rest (the amplitude ramp has ended and the
      // slew-limited command has reached theta_rest), or after retract_time_s at the latest.
      if (controller_.at_rest() ||
          static_cast<double>(mono_us - retract_start_mono_) >= params_.retract_time_s * 1e6) {
        motors_enabled_ = false;
        safety_ = stop_requested_ ? Safety::kStopped : Safety::kDisabled;
      }
      break;
    case Safety::kDisabled:
      if (stop_requested_) {
        safety_ = Safety::kStopped;
      } else if (silent < 0 && all_fresh) {
        safety_ = Safety::kWaiting;  // every board back: start again through the normal path
        reason_ = "bus recovered";
      }
      break;
    case Safety::kFault:
      if (stop_requested_) safety_ = Safety::kStopped;
      break;
    case Safety::kStopped:
      break;
  }
  if (safety_ == Safety::kStopped) reason_ = "stopped on request";
  // Disabled: say what it waits for now (a silent board may be joined by the rest of the bus).
  if (safety_ == Safety::kDisabled) {
    if (stale) {
      reason_ = kBusStaleDisabled;
    } else if (silent >= 0) {
      reason_ = kBoardSilentDisabled[silent];
    }
  }

  rcp::ControlOutput c = controller_.step(in);  // not const: its completed cycle is moved out
  out.cycle = c.cycle;
  out.phase = static_cast<int8_t>(c.phase);
  out.cycle_phase = c.cycle_phase;
  out.enabled = c.enabled && motors_enabled_;
  uint32_t mask = 0;
  for (int w = 0; w < kN; ++w) {
    out.contact[w] = static_cast<float>(c.contact[w]);
    out.theta_ceiling[w] = static_cast<float>(c.theta_ceiling[w]);
    out.theta_command[w] = static_cast<float>(c.theta_command[w]);
    out.command.theta_target[w] = wp::theta_to_counts(c.theta_command[w], params_.calibration[w]);
    constexpr int8_t kMotorOff = whisker_sample_t::STATUS_FAULT | whisker_sample_t::STATUS_OVERTEMP;
    if (motors_enabled_ && !(out.status[w] & kMotorOff)) mask |= 1u << w;
  }
  out.command.enable_mask = mask;
  out.command.seq = ++command_seq_;
  if (c.completed_cycle) {
    // WHISK_CYCLE is in epoch time (slamd matches it against camera and odometry stamps): the
    // whole cycle takes the wall-clock offset of the period that completes it.
    if (pooled_cycles_ > 0) {
      out.completed_cycle = std::move(cycle_pool_[--pooled_cycles_]);
    } else {
      out.completed_cycle = std::make_unique<rcp::WhiskCycle>();  // only if cycles are not handed back
    }
    *out.completed_cycle = std::move(*c.completed_cycle);
    shift_times(*out.completed_cycle, utime - mono_us);
  }
}

bool LineGuard::poll_fault(WhiskerCore& core) {
  if (!lines_.fault_active() || core.safety() == Safety::kFault) return false;
  lines_.set_enable(false);  // first, before anything else this period
  on_ = false;
  core.fault();
  return true;
}

void LineGuard::update(const WhiskerCore& core) {
  if (core.motors_enabled() != on_) {
    on_ = core.motors_enabled();
    lines_.set_enable(on_);
  }
}

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
