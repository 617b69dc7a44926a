// vita-sim speed. The requirement: the default arena run at >= 50x real time. `x_realtime` is
// simulated seconds per wall-clock second of the benchmark loop.
#include "whiskeye/common/bus.h"
#include "whiskeye/sim/lcm_sink.h"
#include "whiskeye/sim/simulator.h"

#include <benchmark/benchmark.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>

namespace {

using namespace whiskeye;
using namespace whiskeye::sim;

World arena() { return load_world_file(WHISKEYE_SOURCE_DIR "/config/worlds/aliased_arena.yaml"); }

Pose2 base_at(const World& w, double deg) {
  Trajectory t = w.trajectory;
  t.start_angle = deg_to_rad(deg);
  return t.pose_at(0.0);
}

void BM_RenderFrame(benchmark::State& state) {
  const World world = arena();
  const RobotGeometry robot = default_robot_geometry();
  Renderer r(world, robot);
  FastRng rng(1);
  std::vector<uint8_t> img;
  const Pose2 pose = base_at(world, 90.0);  // a box and a landmark in view
  for (auto _ : state) {
    r.render(pose, 0.0, rng, img);
    benchmark::DoNotOptimize(img.data());
  }
}
BENCHMARK(BM_RenderFrame)->Unit(benchmark::kMillisecond);

void BM_ContactSweep24(benchmark::State& state) {
  const World world = arena();
  const RobotGeometry robot = default_robot_geometry();
  // range(0) = 1: at a box (sweeps run); 0: between landmarks (pruned).
  const Pose2 head = compose(base_at(world, state.range(0) ? 92.0 : 45.0), robot.T_base_head);
  for (auto _ : state) {
    for (int w = 0; w < kNumWhiskers; ++w) benchmark::DoNotOptimize(find_whisker_contact(world, robot, head, w));
  }
}
BENCHMARK(BM_ContactSweep24)->Arg(0)->Arg(1)->Unit(benchmark::kMicrosecond);

struct NullSink : SimSink {
  void whisker_sample(const rcp::WhiskerSample&, const WhiskerHealth&) override {}
  void rcp_state(const rcp::ControlOutput&) override {}
  void whisk_cycle(const rcp::WhiskCycle&) override {}
  void contact_truth(const ContactTruth&) override {}
  void odometry(int64_t, int64_t, const OdometrySample&) override {}
  void ground_truth(int64_t, const Pose2&) override {}
  void camera(int64_t, int64_t, const std::vector<uint8_t>&, int, int) override {}
  void fault(const FaultEvent&) override {}
};

// One lap of the default arena (62.8 s simulated) per iteration; range(0) = 1 writes the LCM log
// (the world's YUYV frames), 2 writes it with MJPEG frames (quality 85).
void BM_SimulateLap(benchmark::State& state) {
  World world = arena();
  if (state.range(0) == 2) world.camera.format = CameraFormat::Mjpeg;
  const RobotGeometry robot = default_robot_geometry();
  const std::string path = (std::filesystem::temp_directory_path() / ("bench_sim_" + std::to_string(getpid()) + ".lcmlog")).string();
  double simulated = 0.0;
  double wall = 0.0;
  for (auto _ : state) {
    const auto t0 = std::chrono::steady_clock::now();
    SimParams p;
    p.duration = world.trajectory.lap_time();
    Simulator sim(world, robot, rcp::ControllerParams{}, rcp::PlantParams{}, p);
    if (state.range(0)) {
      LogWriterBus bus(path);
      LcmSink sink(bus, [&bus](int64_t t) { bus.set_time(t); }, world.camera, 1.0);
      while (sim.step(sink)) {
      }
    } else {
      NullSink sink;
      while (sim.step(sink)) {
      }
    }
    simulated += sim.duration();
    wall += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  }
  std::filesystem::remove(path);
  state.counters["x_realtime"] = simulated / wall;
}
BENCHMARK(BM_SimulateLap)->Arg(0)->Arg(1)->Arg(2)->Unit(benchmark::kSecond)->Iterations(2)->UseRealTime();

}  // namespace

BENCHMARK_MAIN();
