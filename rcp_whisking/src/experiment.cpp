// Closed-loop controller + plant runs and their figures (see experiment.h).
#include <whiskeye/rcp/experiment.h>

#include <algorithm>
#include <limits>
#include <stdexcept>

namespace whiskeye::rcp {

namespace {

// Per whisker, what happened in the current cycle.
struct CycleTrack {
  bool detected = false;
  int64_t true_contact_utime = -1;
  int64_t detect_utime = -1;
  int64_t react_utime = -1;
  double peak = 0.0;
};

}  // namespace

RunMetrics run_closed_loop(const ControllerParams& controller_params, const PlantParams& plant_params,
                           const ExperimentSpec& spec) {
  if (spec.cycles <= spec.warmup_cycles || spec.warmup_cycles < 0) {
    throw std::invalid_argument("experiment: cycles must exceed warmup_cycles");
  }
  if (spec.period_us <= 0) throw std::invalid_argument("experiment: period_us must be > 0");
  Controller controller(controller_params, 1e6 / static_cast<double>(spec.period_us));
  WhiskerPlant plant(plant_params, spec.seed);
  PerWhisker<bool> in_reach{};
  for (int w = 0; w < kNumWhiskers; ++w) {
    plant.set_obstacle(w, spec.obstacles[w]);
    const auto& o = spec.obstacles[w];
    in_reach[w] = o && o->radial_distance <= plant_params.whisker_length[w] &&
                  o->contact_angle < controller_params.pattern.theta_max;
  }
  controller.enable();

  RunMetrics m;
  PerWhisker<CycleTrack> track{};
  double latency_sum = 0.0;
  double peak_sum = 0.0;
  int peak_count = 0;
  const auto finish_cycle = [&](int64_t cycle) {
    if (cycle <= spec.warmup_cycles) return;
    ++m.cycles_measured;
    for (int w = 0; w < kNumWhiskers; ++w) {
      const CycleTrack& t = track[w];
      if (!in_reach[w]) continue;
      ++m.whisker_cycles_with_obstacle;
      if (t.detected) ++m.whisker_cycles_with_contact;
      m.peak_deflection = std::max(m.peak_deflection, t.peak);
      if (t.true_contact_utime >= 0) {
        peak_sum += t.peak;
        ++peak_count;
      }
      if (t.react_utime >= 0 && t.true_contact_utime >= 0) {
        const double latency = static_cast<double>(t.react_utime - t.true_contact_utime) * 1e-6;
        latency_sum += latency;
        m.reaction_latency_max = std::max(m.reaction_latency_max, latency);
        ++m.reactions;
      }
      if (t.react_utime >= 0 && t.detect_utime >= 0) {
        m.controller_latency_max =
            std::max(m.controller_latency_max, static_cast<double>(t.react_utime - t.detect_utime) * 1e-6);
      }
    }
  };

  PerWhisker<double> command = controller.last_output().theta_command;
  PerWhisker<int64_t> last_true_contact;
  last_true_contact.fill(std::numeric_limits<int64_t>::min() / 2);
  int64_t current_cycle = 0;
  for (int64_t utime = spec.start_utime;; utime += spec.period_us) {
    const WhiskerSample sample = plant.step(utime, command);
    const ControlOutput out = controller.step(sample);
    command = out.theta_command;
    if (out.cycle != current_cycle) {
      if (current_cycle > 0) finish_cycle(current_cycle);
      current_cycle = out.cycle;
      track.fill(CycleTrack{});
      if (current_cycle > spec.cycles) break;
    }
    const bool measured = out.cycle > spec.warmup_cycles;
    const auto& truth = plant.true_state();
    const auto& onset = controller.detector().onset();
    for (int w = 0; w < kNumWhiskers; ++w) {
      CycleTrack& t = track[w];
      if (onset[w]) {
        // A real contact the plant made a moment ago (the whisker hovering at the obstacle's edge) is
        // not a false contact; one with no true contact in the last 20 ms is.
        if (!truth[w].in_contact && out.utime - last_true_contact[w] > 20'000) ++m.false_contacts;
        if (measured) ++m.contact_onsets;
      }
      if (truth[w].in_contact) last_true_contact[w] = out.utime;
      if (out.in_contact[w]) t.detected = true;
      if (truth[w].in_contact && t.true_contact_utime < 0) t.true_contact_utime = out.utime;
      if (out.in_contact[w] && t.detect_utime < 0 && out.phase == Phase::Protract) t.detect_utime = out.utime;
      t.peak = std::max(t.peak, truth[w].contact_deflection);
      if (t.react_utime < 0 && t.true_contact_utime >= 0 && out.theta_ceiling[w] < out.theta_nominal[w] &&
          out.theta_command[w] < out.theta_nominal[w]) {
        t.react_utime = out.utime;
      }
    }
  }
  m.contact_rate = m.whisker_cycles_with_obstacle > 0
                       ? static_cast<double>(m.whisker_cycles_with_contact) / m.whisker_cycles_with_obstacle
                       : 0.0;
  m.mean_cycle_peak_deflection = peak_count > 0 ? peak_sum / peak_count : 0.0;
  m.reaction_latency_mean = m.reactions > 0 ? latency_sum / static_cast<double>(m.reactions) : 0.0;
  return m;
}

ExperimentResult run_experiment(const ControllerParams& controller, const PlantParams& plant,
                                const ExperimentSpec& spec) {
  ExperimentResult result;
  result.rcp = run_closed_loop(controller, plant, spec);
  if (spec.compare_without_rcp) {
    ControllerParams off = controller;
    off.rcp.law = RcpLaw::Off;
    result.without_rcp = run_closed_loop(off, plant, spec);
    if (result.without_rcp->peak_deflection > 0.0) {
      result.peak_reduction = 1.0 - result.rcp.peak_deflection / result.without_rcp->peak_deflection;
    }
  }
  return result;
}

}  // namespace whiskeye::rcp
