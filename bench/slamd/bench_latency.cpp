// slamd-latency-bench: the latency of one full ViTa-SLAM cycle (VitaSlam::process_cycle: visual and
// tactile template building, matching against every stored template, pose cells, experience map with
// relaxation) once the map holds n templates. Figures and the command are in docs/performance.md
// ("## slamd").
//
// The map is grown once per size, untimed, by n cycles at n distinct synthetic places (a smooth
// random 640×480 YUYV view and, at two places in three, a whisk cycle touching 4–11 whiskers), with
// odometry between them, so experiences and links grow with the templates. Then each benchmark
// restores that map and times `kMeasuredCycles` cycles, alternating a new place (a new template,
// experience and link) and a noisy revisit of a random earlier place (normally a match, an
// injection, a loop closure). Counters: p50 / p99 / max of the per-cycle wall time in ms, and the map's size after.
//   BM_CycleLatency/<n>              the core as configured in config/slam.yaml
//   BM_CycleLatencyNoPrefilter/<n>   the same with the matcher's exact lower-bound prefilter off,
//                                    i.e. every stored template compared in full (the plain scan)
#include "whiskeye/slamd/checkpoint_store.h"
#include "whiskeye/slamd/checkpoint_writer.h"
#include "synthetic.h"
#include "whiskeye/slam/vita_slam.h"

#include <benchmark/benchmark.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <map>
#include <random>
#include <thread>

namespace whiskeye::slam {
namespace {

constexpr int kMeasuredCycles = 500;
constexpr int kOdometryPerCycle = 50;  // 50 Hz over a 1 s whisk cycle
constexpr int64_t kCycleUs = 1'000'000;

SlamParams config_params() {
  SlamParams p;
  load(ParamNode::from_file(std::string(WHISKEYE_SOURCE_DIR) + "/config/slam.yaml").section("slam"), p);
  return p;
}

// Place k's camera frame: a 16×12 grid of random intensities, bilinearly interpolated to 640×480
// luma (chroma neutral). Deterministic in k, so a revisit sees exactly the same view.
std::vector<uint8_t> place_frame(int k) {
  constexpr int kW = 640, kH = 480, kGx = 16, kGy = 12;
  std::mt19937 rng(static_cast<uint32_t>(k) * 2654435761u + 1u);
  std::uniform_real_distribution<double> u(0.05, 0.95);
  double grid[kGy + 1][kGx + 1];
  for (auto& row : grid) {
    for (double& v : row) v = u(rng);
  }
  std::vector<uint8_t> yuyv(static_cast<size_t>(kW * kH * 2), 128);
  for (int y = 0; y < kH; ++y) {
    const double gy = static_cast<double>(y) * kGy / kH;
    const int iy = static_cast<int>(gy);
    const double fy = gy - iy;
    for (int x = 0; x < kW; ++x) {
      const double gx = static_cast<double>(x) * kGx / kW;
      const int ix = static_cast<int>(gx);
      const double fx = gx - ix;
      const double v = (1 - fy) * ((1 - fx) * grid[iy][ix] + fx * grid[iy][ix + 1]) +
                       fy * ((1 - fx) * grid[iy + 1][ix] + fx * grid[iy + 1][ix + 1]);
      yuyv[static_cast<size_t>((y * kW + x) * 2)] = static_cast<uint8_t>(std::lround(v * 255.0));
    }
  }
  return yuyv;
}

// The inputs of one cycle at place k, ending at utime_end.
struct PlaceInput {
  std::vector<uint8_t> frame;
  ImageView image;
  WhiskCycleInput whisk;
  CycleInput cycle;
};

// A revisit (noise_seed ≠ 0) sees the place's view with ±4 grey levels of pixel noise and a fresh
// draw of the deflection noise: close to, not equal to, the stored templates.
void make_place(int k, int64_t utime_end, int64_t cycle_no, PlaceInput& in, uint32_t noise_seed = 0) {
  static const RobotGeometry geometry = default_robot_geometry();
  in.frame = place_frame(k);
  if (noise_seed != 0) {
    std::mt19937 rng(noise_seed);
    std::uniform_int_distribution<int> d(-4, 4);
    for (size_t i = 0; i < in.frame.size(); i += 2) {
      in.frame[i] = static_cast<uint8_t>(std::clamp(static_cast<int>(in.frame[i]) + d(rng), 0, 255));
    }
  }
  in.image = ImageView{utime_end, 640, 480, 1280, kPixYuyv, in.frame};
  const bool touches = k % 3 != 0;
  in.whisk = test::whisk_cycle(geometry, touches ? test::random_contacts(static_cast<uint32_t>(k), 4 + k % 8)
                                                 : std::vector<test::SyntheticContact>{},
                               0.003, noise_seed != 0 ? noise_seed : static_cast<uint32_t>(k), utime_end - kCycleUs);
  in.whisk.cycle = cycle_no;
  in.cycle = CycleInput{};
  in.cycle.utime = utime_end;
  in.cycle.cycle = cycle_no;
  in.cycle.image = &in.image;
  in.cycle.whisk = &in.whisk;
  // Walking a wide curve: forward, a little sideways, turning slowly one way then the other.
  const double omega = 0.15 * std::sin(static_cast<double>(cycle_no) / 40.0);
  for (int i = 1; i <= kOdometryPerCycle; ++i) {
    in.cycle.odometry.push_back(
        {utime_end - kCycleUs + i * kCycleUs / kOdometryPerCycle, 0.12, 0.02, omega});
  }
}

// Maps grown to each requested size, serialised (restored for every benchmark run).
struct Grown {
  std::vector<uint8_t> blob;
  int64_t next_utime = 0;
  int64_t next_cycle = 0;
};

const Grown& grown(int n) {
  static std::map<int, Grown> cache;
  const auto it = cache.find(n);
  if (it != cache.end()) return it->second;
  const auto t0 = std::chrono::steady_clock::now();
  VitaSlam slam(config_params(), default_robot_geometry());
  PlaceInput in;
  int64_t utime = 1'700'000'000'000'000;
  for (int k = 0; k < n; ++k) {
    utime += kCycleUs;
    make_place(k, utime, k, in);
    const CycleResult r = slam.process_cycle(in.cycle);
    if (!r.match.is_new) {
      std::fprintf(stderr, "slamd-latency-bench: synthetic place %d matched template %d (error %g): places must be distinct\n", k,
                   r.match.template_id, r.match.error);
      std::abort();
    }
  }
  const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  std::fprintf(stderr, "slamd-latency-bench: grew the map to %d templates, %zu experiences, %zu links in %.1f s\n",
               slam.templates().size(), slam.map().experiences().size(), slam.map().links().size(), s);
  Grown g{slam.serialise(), utime, n};
  return cache.emplace(n, std::move(g)).first->second;
}

void run_latency(benchmark::State& state, const SlamParams& params) {
  const int n = static_cast<int>(state.range(0));
  const Grown& g = grown(n);
  VitaSlam slam = VitaSlam::deserialise(g.blob, params, default_robot_geometry());
  std::mt19937 rng(42);
  std::uniform_int_distribution<int> earlier(0, n - 1);
  std::vector<double> ms, ms_new, ms_revisit;
  ms.reserve(kMeasuredCycles);
  PlaceInput in;
  int64_t utime = g.next_utime;
  int64_t cycle_no = g.next_cycle;
  int new_places = 0, matched_revisits = 0;
  for (auto _ : state) {
    const bool revisit = (cycle_no % 2) == 1;
    const int place = revisit ? earlier(rng) : n + new_places;
    utime += kCycleUs;
    make_place(place, utime, cycle_no, in, revisit ? static_cast<uint32_t>(cycle_no) : 0u);
    const auto t0 = std::chrono::steady_clock::now();
    const CycleResult r = slam.process_cycle(in.cycle);
    const double dt = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    benchmark::DoNotOptimize(r);
    state.SetIterationTime(dt);
    ms.push_back(dt * 1e3);
    (revisit ? ms_revisit : ms_new).push_back(dt * 1e3);
    ++cycle_no;
    if (revisit) {
      matched_revisits += r.match.is_new ? 0 : 1;
    } else {
      ++new_places;
    }
  }
  const double first_ms = ms.empty() ? 0.0 : ms.front();
  const auto at = [](std::vector<double>& v, double q) {
    std::sort(v.begin(), v.end());
    return v.empty() ? 0.0 : v[static_cast<size_t>(q * static_cast<double>(v.size() - 1))];
  };
  state.counters["p50_ms"] = at(ms, 0.50);
  state.counters["p99_ms"] = at(ms, 0.99);
  state.counters["max_ms"] = ms.back();
  state.counters["first_ms"] = first_ms;  // the first cycle after the restore (arrays grow: see docs)
  state.counters["new_p99_ms"] = at(ms_new, 0.99);
  state.counters["revisit_p99_ms"] = at(ms_revisit, 0.99);
  state.counters["templates"] = slam.templates().size();
  state.counters["experiences"] = static_cast<double>(slam.map().experiences().size());
  state.counters["links"] = static_cast<double>(slam.map().links().size());
  state.counters["revisits_matched"] = matched_revisits;
}

void BM_CycleLatency(benchmark::State& state) { run_latency(state, config_params()); }
BENCHMARK(BM_CycleLatency)->Arg(1000)->Arg(10000)->Iterations(kMeasuredCycles)->UseManualTime()->Unit(benchmark::kMillisecond);

void BM_CycleLatencyNoPrefilter(benchmark::State& state) {
  SlamParams p = config_params();
  p.match.lower_bound_prefilter = false;
  run_latency(state, p);
}
BENCHMARK(BM_CycleLatencyNoPrefilter)->Arg(1000)->Arg(10000)->Iterations(kMeasuredCycles)->UseManualTime()->Unit(benchmark::kMillisecond);

// What a live checkpoint of a map of n templates costs slamd's LCM loop, i.e. the time the loop
// cannot receive messages. Written durably by CheckpointStore (temp file, fsync, rename, directory
// fsync) to $TMPDIR (default /tmp; point it at the robot's state disk to measure that).
//   BM_CheckpointSynchronous/<n>  the reference, as slamd did it before: serialise the state, seal
//                                 it and write it, all on the loop's thread
//   BM_CheckpointHandOff/<n>      as slamd does it now: the loop copies the state out and hands it
//                                 to a CheckpointWriter, whose thread seals and writes it
// The time is the loop's; counters: MB per checkpoint; for the hand-off, how many the writer wrote
// and how many a newer one superseded (one is taken every 100 ms here, faster than the disk).
std::string checkpoint_dir() {
  const char* tmp = std::getenv("TMPDIR");
  return std::string(tmp != nullptr ? tmp : "/tmp") + "/slamd-checkpoint-bench";
}

void BM_CheckpointSynchronous(benchmark::State& state) {
  const VitaSlam slam = VitaSlam::deserialise(grown(static_cast<int>(state.range(0))).blob, config_params(),
                                              default_robot_geometry());
  slamd::CheckpointStore store(checkpoint_dir(), 2);
  uint64_t sequence = 0;
  size_t bytes = 0;
  for (auto _ : state) {
    const auto t0 = std::chrono::steady_clock::now();
    const std::vector<uint8_t> blob = slam.serialise();
    store.write(++sequence, blob);
    state.SetIterationTime(std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
    bytes = blob.size();
  }
  state.counters["MB"] = static_cast<double>(bytes) / 1e6;
  std::filesystem::remove_all(checkpoint_dir());
}
BENCHMARK(BM_CheckpointSynchronous)->Arg(1000)->Arg(10000)->Iterations(20)->UseManualTime()->Unit(benchmark::kMillisecond);

void BM_CheckpointHandOff(benchmark::State& state) {
  const VitaSlam slam = VitaSlam::deserialise(grown(static_cast<int>(state.range(0))).blob, config_params(),
                                              default_robot_geometry());
  slamd::CheckpointStore store(checkpoint_dir(), 2);
  slamd::CheckpointWriter writer(
      [&store](uint64_t sequence, std::vector<uint8_t>& payload) {
        VitaSlam::seal(payload);
        store.write(sequence, payload);
      },
      nullptr);
  uint64_t sequence = 0;
  size_t bytes = 0;
  for (auto _ : state) {
    const auto t0 = std::chrono::steady_clock::now();
    std::vector<uint8_t> blob = slam.serialise_unsealed();
    bytes = blob.size();
    writer.submit(++sequence, std::move(blob));
    state.SetIterationTime(std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
    std::this_thread::sleep_for(std::chrono::milliseconds(100));  // the rest of the loop's life
  }
  writer.finish();
  state.counters["MB"] = static_cast<double>(bytes) / 1e6;
  state.counters["written"] = static_cast<double>(writer.counters().written);
  state.counters["superseded"] = static_cast<double>(writer.counters().superseded);
  std::filesystem::remove_all(checkpoint_dir());
}
BENCHMARK(BM_CheckpointHandOff)->Arg(1000)->Arg(10000)->Iterations(20)->UseManualTime()->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace whiskeye::slam

BENCHMARK_MAIN();
