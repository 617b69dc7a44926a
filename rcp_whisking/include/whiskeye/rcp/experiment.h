// Closed-loop runs of the Controller against the WhiskerPlant and the figures that tune RCP:
// contact rate, peak base deflection with and without RCP, reaction latency, false contacts.
// Used by rcp-plant and the tests. Pure (no I/O).
#pragma once

#include <whiskeye/rcp/controller.h>
#include <whiskeye/rcp/plant.h>

#include <optional>

namespace whiskeye::rcp {

struct ExperimentSpec {
  int cycles = 20;                 // whisk cycles to run (after enabling)
  int warmup_cycles = 1;           // first cycles left out of the figures (amplitude ramp)
  int64_t period_us = kControlPeriodUs;  // control period
  int64_t start_utime = 1'000'000; // time of the first sample
  uint64_t seed = 1;
  PerWhisker<std::optional<Obstacle>> obstacles{};
  bool compare_without_rcp = true; // also run with RcpLaw::Off on the same seed
};

struct RunMetrics {
  int cycles_measured = 0;
  int whisker_cycles_with_obstacle = 0;  // measured cycles x whiskers with an obstacle in reach
  int whisker_cycles_with_contact = 0;   // of those, with a detected contact
  double contact_rate = 0.0;             // ratio of the two above
  double peak_deflection = 0.0;          // max true contact deflection |xy| over measured cycles
  double mean_cycle_peak_deflection = 0.0;  // mean over whisker-cycles with contact of the cycle's peak
  // From the first true contact of a whisker-cycle to the first command below the nominal pattern.
  double reaction_latency_mean = 0.0;  // s
  double reaction_latency_max = 0.0;   // s
  // From the detector's onset to the first command below the nominal pattern (the controller's own
  // latency; 0 means the same step).
  double controller_latency_max = 0.0;  // s
  int64_t reactions = 0;
  int64_t false_contacts = 0;  // detector onsets with no true plant contact in the last 20 ms
  int64_t contact_onsets = 0;  // all detector onsets in measured cycles
};

struct ExperimentResult {
  RunMetrics rcp;
  std::optional<RunMetrics> without_rcp;
  double peak_reduction = 0.0;  // 1 - peak(rcp) / peak(without), when compared
};

RunMetrics run_closed_loop(const ControllerParams& controller, const PlantParams& plant,
                           const ExperimentSpec& spec);
ExperimentResult run_experiment(const ControllerParams& controller, const PlantParams& plant,
                                const ExperimentSpec& spec);

}  // namespace whiskeye::rcp
