// whiskerd's control core, free of sockets, threads and clocks so it is unit-tested and benchmarked
// on the host: frames in (on_frame), one control period out (step) — latest sample of every board
// -> calibration -> rcp_whisking controller -> motor command -> the messages to publish — plus the
// safety state machine (GPIO fault: motors off at once and latched; stop request, stale bus or a
// silent board: retract, then drop enable). The daemon (ControlLoop,
// control_loop.h, and src/main.cpp) is the thin wiring around it; whiskerd.yaml and its drop-ins are
// loaded by config.h, the outputs converted to LCM messages by lcm.h.
#pragma once

#include <whiskeye/rcp/controller.h>

#include <array>
#include <cstdint>
#include <memory>
#include <optional>
#include <span>
#include <string>

#include "whiskeye/common/latency_stats.h"
#include "whiskeye/gpio/motor_lines.h"
#include "whiskeye/whisker_protocol/whisker_protocol.h"

namespace whiskeye::whiskerd {

constexpr int kN = kNumWhiskers;

constexpr std::array<int, kN> identity_wiring() {
  std::array<int, kN> a{};
  for (int w = 0; w < kN; ++w) a[w] = w;
  return a;
}

// Per-whisker status bits of a period (PeriodOutput::status), the values of whisker_sample_t's
// STATUS_* (checked where the LCM conversion lives, lcm.cpp).
inline constexpr int8_t kStatusStale = 1;      // no fresh sample from the whisker's board this period
inline constexpr int8_t kStatusSaturated = 2;  // Hall reading at the ADC limit
inline constexpr int8_t kStatusFault = 4;      // the board reports a fault: reading invalid, motor off
inline constexpr int8_t kStatusOvertemp = 8;   // board over temperature: motor off, reading valid

// What the control core needs (WhiskerCore): the bus's frame format and rate, the safety timings,
// the calibration and the whisking controller.
struct CoreParams {
  // can
  wp::BusMode mode = wp::BusMode::kFd;
  wp::ProtocolIds ids;
  double rate_hz = 500.0;         // control and sample rate
  double stale_timeout_s = 0.1;   // a board without a fresh sample for this long -> retract, drop enable
  // safety
  double retract_time_s = 1.0;    // longest time to wait for the retraction ramp before dropping enable
  bool whisk_on_start = true;     // start whisking as soon as every board is streaming
  // calibration, per whisker
  std::array<wp::WhiskerCalibration, kN> calibration{};
  // wiring: channel[w] is the board channel (board * 4 + k) whose Hall sensor, encoder and motor are
  // whisker w's; a permutation of 0..23 (the identity as the boards are meant to be wired).
  std::array<int, kN> channel = identity_wiring();
  // the whisking controller (section `rcp`: pattern, detector, rcp)
  rcp::ControllerParams controller;
};

// Everything one control period produces, as plain data. A completed cycle comes from the core's
// pool; hand it back with WhiskerCore::recycle() once published so that step() never allocates.
struct PeriodOutput {
  int64_t utime = 0;
  int64_t seq = 0;
  std::array<float, kN> theta{}, deflection_x{}, deflection_y{};
  std::array<int16_t, kN> raw_x{}, raw_y{}, raw_theta{};
  std::array<int8_t, kN> status{};
  int64_t cycle = 0;
  int8_t phase = 2;
  double cycle_phase = 0;
  bool enabled = false;
  std::array<float, kN> contact{}, theta_ceiling{}, theta_command{};
  wp::MotorCommand command;
  std::unique_ptr<rcp::WhiskCycle> completed_cycle;
};

enum class Safety { kWaiting, kRunning, kRetracting, kDisabled, kFault, kStopped };
const char* safety_name(Safety s);

// Counter names, in the order of Counters::values (DRIVER_STATUS counter_names).
struct Counters {
  static constexpr int kFixed = 16;
  static constexpr int kCount = kFixed + wp::kNumBoards;
  static const char* const kNames[kCount];
  std::array<int64_t, kCount> values{};
  int64_t& operator[](int i) { return values[i]; }
  enum : int {
    kFrames = 0, kSamples, kHeartbeats, kRejectedUnknownId, kRejectedWrongLength, kRejectedOutOfRange,
    kRejectedWrongFrameType, kGaps, kIncomplete, kStaleBoardPeriods, kDeadlineMisses, kPublishDrops,
    kCanTxErrors, kLateSamples, kBoardResyncs, kOvertempBoardPeriods, kGapsBoard0
  };
  static_assert(kGapsBoard0 == kFixed, "the per-board counters follow the fixed ones");
};

class WhiskerCore {
 public:
  // Throws std::invalid_argument if params.channel is not a permutation (load() never gives one).
  explicit WhiskerCore(const CoreParams& params);

  // One received frame; mono_us is the receive time on the monotonic clock.
  void on_frame(uint32_t id, bool fd, std::span<const uint8_t> data, int64_t mono_us);
  // One control period: utime = epoch time of the period, mono_us = the monotonic clock. The
  // controller runs on mono_us; the outputs (PeriodOutput::utime, a completed cycle's times) are
  // epoch, a completed cycle shifted by this period's utime - mono_us.
  // A completed cycle still in `out` from an earlier period is recycled first.
  void step(int64_t utime, int64_t mono_us, PeriodOutput& out);
  // Gives back a completed cycle once it is published (from any thread's hands, but called on the
  // control thread): its sample storage goes back to the controller and the object to the pool, so
  // the next completions reuse both instead of allocating. Null is ignored.
  void recycle(std::unique_ptr<rcp::WhiskCycle> used);

  // GPIO fault or emergency stop: motors off from this period on, latched until restart.
  void fault();
  // SIGTERM or a fatal error: retract, drop enable, then finished().
  void request_stop();
  bool finished() const { return safety_ == Safety::kStopped; }
  // What the enable line should be.
  bool motors_enabled() const { return motors_enabled_; }
  Safety safety() const { return safety_; }
  // Staleness counts fresh samples only (accepted by the assembler: not duplicates, late, rejected
  // or heartbeat frames). The bus is stale when no board has had one for stale_timeout_s;
  // silent_board() is the first board without one for that long (-1: none).
  bool bus_stale(int64_t mono_us) const;
  int silent_board(int64_t mono_us) const;
  const char* reason() const { return reason_; }

  // Rejected frames are counted (rejected_<reason>) and the 1st, 10th, 100th, ... of them is kept
  // here as one line naming what was wrong, formatted without allocating, until the control loop
  // takes it for the log: null when there is none. rejected_frames() counts them all.
  const char* take_rejection_line();
  int64_t rejected_frames() const { return rejected_frames_; }

  Counters& counters() { return counters_; }
  const wp::SampleAssembler& assembler() const { return assembler_; }
  const rcp::Controller& controller() const { return controller_; }

 private:
  void start_retract(int64_t mono_us, const char* why);
  bool timed_out(int64_t last_mono, int64_t mono_us) const;

  // Cycle objects waiting for the next completion. Two are made up front; a cycle that is never
  // handed back (a dropped period) only costs one allocation at a later completion.
  static constexpr int kCyclePool = 4;

  CoreParams params_;
  rcp::Controller controller_;
  std::array<std::unique_ptr<rcp::WhiskCycle>, kCyclePool> cycle_pool_;
  int pooled_cycles_ = 0;
  wp::SampleAssembler assembler_;
  std::array<double, kN> cos_r_{}, sin_r_{};
  std::array<int, kN> whisker_of_channel_{};  // inverse of params_.channel
  std::array<int64_t, wp::kNumBoards> used_samples_{};  // board sample count consumed last period
  std::array<int64_t, wp::kNumBoards> last_sample_mono_;  // per board, time of its last fresh sample; -1 = none
  int64_t seq_ = 0;
  uint16_t command_seq_ = 0;
  Safety safety_ = Safety::kWaiting;
  bool stop_requested_ = false;
  bool motors_enabled_ = false;
  int64_t retract_start_mono_ = 0;
  const char* reason_ = "waiting for every board";
  Counters counters_;
  int64_t rejected_frames_ = 0;
  int64_t next_rejection_to_log_ = 1;
  bool rejection_pending_ = false;
  std::array<char, wp::kRejectTextBytes> rejection_line_{};
};

// Couples the motor lines to the core, once per period: poll_fault() before step() (a fault or
// e-stop drops the enable line at once, then latches the core in Safety::kFault); update() after
// step() makes the enable line follow motors_enabled().
class LineGuard {
 public:
  explicit LineGuard(gpio::MotorLines& lines) : lines_(lines) { lines_.set_enable(false); }
  // True if a new fault was seen this call.
  bool poll_fault(WhiskerCore& core);
  void update(const WhiskerCore& core);
  bool enabled() const { return on_; }

 private:
  gpio::MotorLines& lines_;
  bool on_ = false;
};

// Status of one reporting interval, as plain data pushed through the ring by the control thread.
struct StatusSnapshot {
  int64_t utime = 0;
  Safety safety = Safety::kWaiting;
  const char* reason = "";
  const char* bus_state = "";
  std::array<int64_t, Counters::kCount> counters{};
  int64_t can_rx = 0, can_error_frames = 0, can_bus_off = 0, can_error_passive = 0, can_reopens = 0,
          can_rx_overflow = 0;
  LatencySummary wake_latency;  // clock_nanosleep deadline -> running
  LatencySummary loop_time;     // work per period
  LatencySummary period_jitter; // |actual period - nominal|
  bool rt_scheduling = false;
};

}  // namespace whiskeye::whiskerd
