// Speed of whiskerd's hot path: (1) frame decode + calibration + publish (LCM encode onto a Bus),
// per CAN frame, budget 10 us; (2) one whole control period of WhiskerCore (6 frames in, controller,
// motor command out), budget 50 us.
#include <benchmark/benchmark.h>

#include <whiskeye/common/bus.h>
#include <whiskeye/rcp_state_t.hpp>
#include <whiskeye/whisker_sample_t.hpp>

#include <array>
#include <vector>

#include "whiskeye/whiskerd/config.h"
#include "whiskeye/whiskerd/lcm.h"
#include "whiskeye/whiskerd/whiskerd_core.h"
#include "whiskeye/whisker_protocol/whisker_protocol.h"

using namespace whiskeye;

namespace {

// One period's worth of board frames with slowly varying values.
std::vector<std::array<uint8_t, 32>> make_frames(int seq) {
  std::vector<std::array<uint8_t, 32>> frames(wp::kNumBoards);
  for (int b = 0; b < wp::kNumBoards; ++b) {
    wp::BoardSample s;
    s.board = b;
    s.seq = static_cast<uint16_t>(seq);
    for (int k = 0; k < 4; ++k) {
      s.whiskers[k] = {static_cast<int16_t>((seq * 7 + k) % 200), static_cast<int16_t>(-(seq % 100)),
                       static_cast<int16_t>((seq * 3) % 600 - 300), false};
    }
    wp::encode_sample_fd(s, frames[b]);
  }
  return frames;
}

class NullBus : public Bus {
 public:
  void publish_raw(const std::string&, std::span<const uint8_t> data) override { bytes += data.size(); }
  void subscribe_raw(const std::string&, RawHandler) override {}
  std::size_t bytes = 0;
};

void BM_FrameDecodeCalibratePublish(benchmark::State& state) {
  std::array<wp::WhiskerCalibration, wp::kNumWhiskers> cal{};
  for (int w = 0; w < wp::kNumWhiskers; ++w) cal[w].rotation = 0.01 * w;
  wp::SampleAssembler assembler(wp::BusMode::kFd);
  wp::DecodeCounters counters;
  NullBus bus;
  whisker_sample_t msg;
  msg.num_whiskers = wp::kNumWhiskers;
  msg.theta.resize(24);
  msg.deflection_x.resize(24);
  msg.deflection_y.resize(24);
  msg.raw_x.resize(24);
  msg.raw_y.resize(24);
  msg.raw_theta.resize(24);
  msg.status.resize(24);
  int seq = 0;
  auto frames = make_frames(0);
  for (auto _ : state) {
    // One frame per iteration: decode, assemble, calibrate its 4 whiskers into the message, publish.
    const int b = seq % wp::kNumBoards;
    if (b == 0) frames = make_frames(seq / wp::kNumBoards);
    const wp::Decoded d = wp::decode_frame(wp::sample_id({}, b), true, frames[b], wp::BusMode::kFd);
    counters.count(d);
    assembler.add(d.sample);
    for (int k = 0; k < 4; ++k) {
      const int w = 4 * b + k;
      const wp::CalibratedWhisker c = wp::calibrate(d.sample.whiskers[k], cal[w]);
      msg.theta[w] = c.theta;
      msg.deflection_x[w] = c.x;
      msg.deflection_y[w] = c.y;
      msg.raw_x[w] = d.sample.whiskers[k].x;
      msg.raw_y[w] = d.sample.whiskers[k].y;
      msg.raw_theta[w] = d.sample.whiskers[k].theta;
    }
    msg.seq = seq;
    publish(bus, "WHISKER_SAMPLE", msg);
    ++seq;
  }
  benchmark::DoNotOptimize(bus.bytes);
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_FrameDecodeCalibratePublish);

// One whole control period of WhiskerCore (6 frames in, controller, motor command out); with
// `publish`, also the publisher thread's share (LCM conversion and encode of both messages).
void control_period(benchmark::State& state, bool publish_too) {
  whiskerd::Params p;
  p.controller.detector.learn_cycles = 0;
  whiskerd::WhiskerCore core(p);
  whiskerd::PeriodOutput out;
  NullBus bus;
  whisker_sample_t sample;
  rcp_state_t rcp;
  int64_t mono = 1000000, utime = 1700000000000000;
  int seq = 0;
  std::vector<std::vector<std::array<uint8_t, 32>>> periods;
  for (int i = 0; i < 500; ++i) periods.push_back(make_frames(i));
  for (auto _ : state) {
    const auto& frames = periods[seq % periods.size()];
    for (int b = 0; b < wp::kNumBoards; ++b) core.on_frame(wp::sample_id({}, b), true, frames[b], mono);
    mono += 2000;
    utime += 2000;
    core.step(utime, mono, out);
    benchmark::DoNotOptimize(out.command);
    if (publish_too) {
      whiskerd::to_lcm(out, sample, rcp);
      publish(bus, "WHISKER_SAMPLE", sample);
      publish(bus, "RCP_STATE", rcp);
    }
    ++seq;
  }
  benchmark::DoNotOptimize(bus.bytes);
  state.SetItemsProcessed(state.iterations());
}
void BM_ControlPeriod(benchmark::State& state) { control_period(state, false); }
void BM_ControlPeriodAndPublish(benchmark::State& state) { control_period(state, true); }
BENCHMARK(BM_ControlPeriod);
BENCHMARK(BM_ControlPeriodAndPublish);

}  // namespace

BENCHMARK_MAIN();
