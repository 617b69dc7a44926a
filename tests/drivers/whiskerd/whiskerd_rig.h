// A whiskerd core fed with every board's samples, one control period at a time, for the core's
// unit and allocation tests.
#pragma once

#include <array>
#include <cmath>
#include <cstdint>

#include "whiskeye/whiskerd/config.h"
#include "whiskeye/whiskerd/whiskerd_core.h"

namespace whiskeye::whiskerd::test {

constexpr int64_t kPeriod = 2000;

inline Params test_params() {
  Params p;
  p.controller.detector.learn_cycles = 0;
  p.stale_timeout_s = 0.02;
  p.retract_time_s = 0.2;
  return p;
}

// Feeds one sample of every board (one board optionally missing) and runs one period.
struct Rig {
  explicit Rig(const Params& p = test_params()) : core(p), period(std::llround(1e6 / p.rate_hz)) {}
  void send(int b, int seq, int16_t x5 = 20) {
    wp::BoardSample s;
    s.board = b;
    s.seq = static_cast<uint16_t>(seq);
    for (int k = 0; k < 4; ++k) {
      const int w = 4 * b + k;
      s.whiskers[k] = {static_cast<int16_t>(w == 5 ? x5 : w), static_cast<int16_t>(-w), static_cast<int16_t>(10 * w), false};
    }
    std::array<uint8_t, 32> buf{};
    wp::encode_sample_fd(s, buf);
    core.on_frame(wp::sample_id({}, b), true, buf, mono);
  }
  void feed(int seq, int16_t x5 = 20, int skip_board = -1) {
    for (int b = 0; b < wp::kNumBoards; ++b) {
      if (b != skip_board) send(b, seq, x5);
    }
  }
  void heartbeat(int b, uint8_t state = 0x05) {
    std::array<uint8_t, 2> buf{};
    wp::encode_heartbeat({b, state, 0}, buf);
    core.on_frame(wp::heartbeat_id({}, b), false, buf, mono);
  }
  void heartbeats() {
    for (int b = 0; b < wp::kNumBoards; ++b) heartbeat(b);
  }
  void step() {
    mono += period;
    utime += period;
    core.step(utime, mono, out);
  }
  void run(int periods, int16_t x5 = 20) {
    for (int i = 0; i < periods; ++i) {
      feed(seq++, x5);
      step();
    }
  }
  WhiskerCore core;
  PeriodOutput out;
  int64_t mono = 1000000, utime = 1700000000000000;
  int seq = 0;
  int64_t period;  // us, from Params::rate_hz
};

}  // namespace whiskeye::whiskerd::test
