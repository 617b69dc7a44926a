// The whisking controller: pattern generator + contact detector + rapid cessation of protraction
// (RCP) + whisk-cycle assembler, stepped once per sample (500 Hz on WhiskEye). Pure: the controller's time is the
// sample's utime (no clock reads, no I/O); the same code runs in whiskerd and in vita-sim.
// step() is allocation-free except at the step that completes a whisk cycle.
#pragma once

#include <whiskeye/common/whisker_array.h>
#include <whiskeye/rcp/contact_detector.h>
#include <whiskeye/rcp/cycle_assembler.h>
#include <whiskeye/rcp/params.h>
#include <whiskeye/rcp/pattern.h>
#include <whiskeye/rcp/types.h>

#include <optional>

namespace whiskeye::rcp {

struct ControlOutput {
  int64_t utime = 0;
  int64_t cycle = 0;           // current whisk cycle number (0 before the first)
  Phase phase = Phase::Rest;   // master (row 0 without lead) phase
  double cycle_phase = 0.0;    // 0..1 within the current cycle
  bool enabled = false;        // enable() was called and disable() not since
  PerWhisker<double> theta_command{};  // rad, what the motors should track
  PerWhisker<double> theta_ceiling{};  // rad, RCP ceiling (theta_max when no contact this cycle)
  PerWhisker<double> theta_nominal{};  // rad, the pattern alone (with the enable/disable ramp)
  PerWhisker<double> contact{};        // contact level 0..1
  PerWhisker<bool> in_contact{};       // detector state (hysteresis)
  std::optional<WhiskCycle> completed_cycle;  // set at the step that starts the next cycle
};

// Counters for status reporting.
struct ControllerStats {
  int64_t steps = 0;
  int64_t rejected_samples = 0;   // utime not increasing: ignored, last output repeated
  int64_t missing_samples = 0;    // sum of sequence gaps
  int64_t cycles_emitted = 0;
  int64_t cycles_discarded = 0;   // partial cycles dropped when whisking stopped
};

class Controller {
 public:
  // sample_rate_hz: how often step() is called. It sizes the whisk-cycle storage reserved up front
  // (a cycle holds sample_rate_hz / frequency_hz samples), so a faster loop does not grow it
  // mid-cycle, and sets the assembler's nominal sample period.
  explicit Controller(const ControllerParams& params, double sample_rate_hz = kControlRateHz);

  // One control period. Returns the command for this period computed from this sample (the
  // reaction to a contact seen in this sample is already in theta_command).
  ControlOutput step(const WhiskerSample& sample);

  // Start whisking at the next step(): the pattern starts at theta_min and the amplitude ramps up
  // over ramp_time. Re-enabling during a disable ramp resumes without a phase jump.
  void enable();
  // Stop whisking: the amplitude ramps down to theta_rest over ramp_time, then phase = Rest and
  // the cycle in progress is discarded.
  void disable();
  bool enabled() const { return enabled_; }
  // Optional: hand a completed cycle back after publishing it, so its storage is reused and the
  // real-time loop never allocates (otherwise each cycle completion allocates one sample vector).
  void recycle(WhiskCycle&& used) { assembler_.recycle(std::move(used)); }
  // The pattern clock is running (whisking, or ramping down after disable()).
  bool running() const { return running_; }
  // Stopped and every command back at theta_rest: the slew limit may hold the command away from
  // rest for a while after the amplitude ramp has ended (ramp_time 0, a low max_rate).
  bool at_rest() const;

  const ControllerParams& params() const { return params_; }
  const ContactDetector& detector() const { return detector_; }
  const ControllerStats& stats() const { return stats_; }
  const ControlOutput& last_output() const { return out_; }

 private:
  void reset_cycle_state(int w);

  ControllerParams params_;
  double nominal_period_s_;  // 1 / sample rate: bounds the slew step after a stall
  PatternGenerator pattern_;
  ContactDetector detector_;
  CycleAssembler assembler_;
  ControllerStats stats_;
  ControlOutput out_;

  bool enabled_ = false;
  bool running_ = false;           // pattern clock running (enabled or ramping down)
  bool have_last_ = false;
  int64_t last_utime_ = 0;
  int64_t last_seq_ = 0;
  int64_t origin_utime_ = 0;       // time of the first cycle's start
  int64_t origin_cycle_ = 0;       // cycle number before the first cycle of this run
  int64_t free_cycles_ = 0;        // cycle starts seen while enabled (drives noise-floor learning)
  double envelope_ = 0.0;          // 0..1 amplitude ramp state (linear; smoothed when applied)
  PerWhisker<int64_t> row_cycle_{};     // per whisker, the cycle of its own (row) phase
  PerWhisker<double> contact_max_{};    // running max of the contact level within the cycle
  PerWhisker<double> hold_{};           // freeze_on_contact cap (+inf until a contact this cycle)
  PerWhisker<double> ceiling_{};        // current ceiling
  PerWhisker<double> command_{};        // last command
};

}  // namespace whiskeye::rcp
