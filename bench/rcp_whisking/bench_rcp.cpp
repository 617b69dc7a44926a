// rcp-bench: cost of one control step (24 whiskers) of the whisking controller, which runs inside
// whiskerd's 500 Hz real-time loop (budget 5 us), plus the plant model and the cycle assembler.
#include <benchmark/benchmark.h>
#include <whiskeye/rcp/rcp.h>

#include <algorithm>
#include <chrono>
#include <optional>
#include <cmath>
#include <vector>

namespace {

using namespace whiskeye;
using namespace whiskeye::rcp;

constexpr int64_t kPeriodUs = 2000;

// Recorded closed-loop samples (free whisking, or with obstacles on every whisker) to replay.
std::vector<WhiskerSample> record(bool obstacles, int n) {
  ControllerParams cp;
  PlantParams pp;
  Controller c(cp);
  WhiskerPlant plant(pp, 5);
  if (obstacles) {
    for (int w = 0; w < kNumWhiskers; ++w) {
      plant.set_obstacle(w, Obstacle{deg_to_rad(-10.0 + 5.0 * (w % 6)), 0.6 * pp.whisker_length[w]});
    }
  }
  c.enable();
  std::vector<WhiskerSample> out;
  PerWhisker<double> cmd = c.last_output().theta_command;
  for (int i = 0; i < n; ++i) {
    out.push_back(plant.step(i * kPeriodUs, cmd));
    cmd = c.step(out.back()).theta_command;
  }
  return out;
}

void run_controller(benchmark::State& state, bool obstacles) {
  const std::vector<WhiskerSample> samples = record(obstacles, 5000);
  Controller c{ControllerParams{}};
  c.enable();
  WhiskerSample s = samples[0];
  int64_t k = 0;
  int64_t completed = 0;
  for (auto _ : state) {
    // Replay the recording with time running on (the controller rejects time going back).
    const WhiskerSample& src = samples[static_cast<std::size_t>(k % 5000)];
    s.deflection_x = src.deflection_x;
    s.deflection_y = src.deflection_y;
    s.theta = src.theta;
    s.utime = k * kPeriodUs;
    s.seq = k;
    ++k;
    ControlOutput out = c.step(s);
    completed += out.completed_cycle.has_value();
    benchmark::DoNotOptimize(out.theta_command.data());
  }
  state.counters["cycles_emitted"] = static_cast<double>(completed);
}

// The whole control step, amortised over whisk cycles (one in 500 steps also hands over a cycle).
void BM_ControllerStep_FreeWhisking(benchmark::State& state) { run_controller(state, false); }
void BM_ControllerStep_AllWhiskersTouching(benchmark::State& state) { run_controller(state, true); }

// The bare WhiskEye law (pattern, c = clip(5 (|xy| - 0.04)), running max, ceiling, min) for 24
// whiskers, without detection learning, hysteresis, ramps, slew limits or cycle assembly: for scale.
void BM_ReferenceWhiskEyeLaw(benchmark::State& state) {
  const std::vector<WhiskerSample> samples = record(true, 5000);
  const double tmin = deg_to_rad(-30.0);
  const double tmax = deg_to_rad(45.0);
  const double trcp = deg_to_rad(-60.0);
  PerWhisker<double> m{};
  PerWhisker<double> cmd{};
  int64_t k = 0;
  double last_phase = 0.0;
  for (auto _ : state) {
    const WhiskerSample& s = samples[static_cast<std::size_t>(k % 5000)];
    const double t = static_cast<double>(k) * 0.002;
    ++k;
    const double phase = t - std::floor(t);
    if (phase < last_phase) m.fill(0.0);
    last_phase = phase;
    const double nominal = tmin + (0.5 + 0.5 * std::sin(kTwoPi * t)) * (tmax - tmin);
    for (int w = 0; w < kNumWhiskers; ++w) {
      const double c = std::clamp(5.0 * (std::hypot(s.deflection_x[w], s.deflection_y[w]) - 0.04), 0.0, 1.0);
      m[w] = std::max(m[w], c);
      cmd[w] = std::min(nominal, tmax + m[w] * (trcp - tmax));
    }
    benchmark::DoNotOptimize(cmd.data());
  }
}

// Only the step that completes a whisk cycle (it hands over 500 samples and, unless the caller
// recycles the previous cycle, allocates the next cycle's storage). Timed by hand around that step.
void run_completion(benchmark::State& state, bool recycle) {
  Controller c{ControllerParams{}};
  c.enable();
  WhiskerSample s;
  s.valid.fill(true);
  int64_t k = 0;
  std::optional<WhiskCycle> held;
  for (auto _ : state) {
    ControlOutput out;
    // Untimed up to the last sample of the cycle; sample k = 500 n starts cycle n + 1.
    for (;;) {
      s.utime = k * kPeriodUs;
      s.seq = k;
      ++k;
      if (s.seq > 0 && s.seq % 500 == 0) break;
      out = c.step(s);
    }
    const auto t0 = std::chrono::steady_clock::now();
    out = c.step(s);
    const auto t1 = std::chrono::steady_clock::now();
    state.SetIterationTime(std::chrono::duration<double>(t1 - t0).count());
    if (!out.completed_cycle) state.SkipWithError("no cycle completed at the timed step");
    if (out.completed_cycle && recycle) c.recycle(std::move(*out.completed_cycle));
    held = std::move(out.completed_cycle);  // freed outside the timed step
  }
}
void BM_ControllerStep_CycleCompletion(benchmark::State& state) { run_completion(state, false); }
void BM_ControllerStep_CycleCompletionRecycled(benchmark::State& state) { run_completion(state, true); }

void BM_PlantStep(benchmark::State& state) {
  WhiskerPlant plant(PlantParams{}, 1);
  for (int w = 0; w < kNumWhiskers; ++w) plant.set_obstacle(w, Obstacle{0.1, 0.05});
  PerWhisker<double> cmd{};
  int64_t k = 0;
  for (auto _ : state) {
    cmd.fill(0.5 * std::sin(static_cast<double>(k) * 0.0126));
    WhiskerSample s = plant.step(++k * kPeriodUs, cmd);
    benchmark::DoNotOptimize(s.deflection_x.data());
  }
}

void BM_AssemblerPush(benchmark::State& state) {
  CycleAssembler a;
  WhiskerSample s;
  s.valid.fill(true);
  PerWhisker<bool> contact{};
  int64_t k = 0;
  for (auto _ : state) {
    s.seq = k;
    s.utime = k * kPeriodUs;
    CycleTag tag;
    tag.cycle = k / 500 + 1;
    tag.cycle_start_utime = (k / 500) * 500 * kPeriodUs;
    tag.retract_start_utime = tag.cycle_start_utime + 250 * kPeriodUs;
    ++k;
    auto done = a.push(s, tag, contact);
    benchmark::DoNotOptimize(done);
  }
}

}  // namespace

BENCHMARK(BM_ControllerStep_FreeWhisking);
BENCHMARK(BM_ControllerStep_AllWhiskersTouching);
// Each iteration steps through a whole cycle untimed: a fixed iteration count keeps the run short.
BENCHMARK(BM_ControllerStep_CycleCompletion)->UseManualTime()->Iterations(300);
BENCHMARK(BM_ControllerStep_CycleCompletionRecycled)->UseManualTime()->Iterations(300);
BENCHMARK(BM_ReferenceWhiskEyeLaw);
BENCHMARK(BM_PlantStep);
BENCHMARK(BM_AssemblerPush);

BENCHMARK_MAIN();
