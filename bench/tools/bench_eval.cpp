// eval-bench: what vita-eval's metrics cost as the map grows (docs/performance.md, "## vita-eval").
// A synthetic run of N experiences on a circle, one event and a few pose and ground-truth samples per
// experience, links along the path and a loop closure every tenth: every metric of evaluate() has
// work in proportion to N, so the time per experience stays flat if nothing is quadratic.
#include "whiskeye/eval/metrics.h"

#include <benchmark/benchmark.h>

#include <cmath>
#include <cstdint>

namespace {

using namespace whiskeye;
using namespace whiskeye::eval;

EvalInput synthetic_run(int n) {
  EvalInput in;
  constexpr int64_t kT0 = 1'700'000'000'000'000;
  constexpr int64_t kStep_us = 200'000;
  const double r = 2.0;
  for (int i = 0; i < n; ++i) {
    const int64_t t = kT0 + i * kStep_us;
    const double a = 2.0 * M_PI * 4.0 * i / n;  // four laps
    const Pose2 truth{r * std::cos(a), r * std::sin(a), a + M_PI / 2.0};
    const Pose2 est{truth.x + 0.01, truth.y - 0.01, truth.theta};
    in.ground_truth.push_back({t, truth});
    in.estimate.push_back({t, est});
    in.map.experiences.push_back({i, est, t, false});
    if (i > 0) in.map.links.push_back({i - 1, i, false, {}});
    const bool reloc = i >= n / 4 && i % 10 == 0;
    if (reloc) in.map.links.push_back({i, i - n / 4, false, {}});
    in.events.push_back({t, i, reloc ? EventType::kRelocalise : EventType::kNewExperience, i - 1,
                         reloc ? i - n / 4 : i});
  }
  return in;
}

void BM_Evaluate(benchmark::State& state) {
  const EvalInput in = synthetic_run(static_cast<int>(state.range(0)));
  const EvalParams params;
  for (auto _ : state) benchmark::DoNotOptimize(evaluate(in, params));
  state.counters["experiences"] = static_cast<double>(state.range(0));
  state.counters["ns_per_experience"] = benchmark::Counter(
      static_cast<double>(state.range(0)), benchmark::Counter::kIsIterationInvariantRate | benchmark::Counter::kInvert);
}
BENCHMARK(BM_Evaluate)->Arg(20'000)->Arg(100'000)->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
