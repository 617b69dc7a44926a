// whiskerd's control core (see whiskerd_core.h).
#include "whiskeye/whiskerd/whiskerd_core.h"

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <stdexcept>
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

}  // namespace

WhiskerCore::WhiskerCore(const CoreParams& params)
    : params_(params), controller_(params.controller, params.rate_hz), assembler_(params.mode) {
  last_sample_mono_.fill(-1);
  for (; pooled_cycles_ < 2; ++pooled_cycles_) cycle_pool_[pooled_cycles_] = std::make_unique<rcp::WhiskCycle>();
  std::array<bool, kN> wired{};
  for (int w = 0; w < kN; ++w) {
    const int ch = params_.channel[w];
    if (ch < 0 || ch >= kN || wired[ch]) {
      throw std::invalid_argument("whiskerd: calibration channels are not a permutation of 0..23");
    }
    wired[ch] = true;
    whisker_of_channel_[ch] = w;
  }
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
      const int w = whisker_of_channel_[b * wp::kWhiskersPerBoard + k];
      const wp::WhiskerRaw& raw = s.whiskers[k];
      int8_t status = 0;
      if (!fresh) status |= kStatusStale;
      if (have && (std::abs(raw.x) >= wp::kHallLimit || std::abs(raw.y) >= wp::kHallLimit)) {
        status |= kStatusSaturated;
      }
      const bool faulty = have && (raw.fault || (s.status & wp::kBoardFault));
      if (faulty) status |= kStatusFault;
      if (overtemp) status |= kStatusOvertemp;
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
    // The boards take targets by channel: whisker w's motor is on channel[w].
    const int ch = params_.channel[w];
    out.command.theta_target[ch] = wp::theta_to_counts(c.theta_command[w], params_.calibration[w]);
    constexpr int8_t kMotorOff = kStatusFault | kStatusOvertemp;
    if (motors_enabled_ && !(out.status[w] & kMotorOff)) mask |= 1u << ch;
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

}  // namespace whiskeye::whiskerd
