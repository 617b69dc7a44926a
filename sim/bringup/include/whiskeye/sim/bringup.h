// Simulated bring-up sessions of a new WhiskEye (docs/bring-up.md, docs/simulator.md "Bring-up
// sessions"): what its whiskers measure while the operator runs whiskeye-calibrate — at rest, tapped
// one by one, swept through the joint range, deflected on a jig — and a drawn "true" calibration of
// the boards (offsets, gains, rotations, θ offset and gain, two whiskers plugged into each other's
// sockets, one board mounted mirrored). The samples go through sim::BoardTraffic with the true
// calibration as its whiskerd calibration, so the boards' frames are what that robot would send.
// Pure: time and seed are arguments.
#pragma once

#include <whiskeye/rcp/types.h>

#include <array>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "whiskeye/sim/simulator.h"
#include "whiskeye/whisker_protocol/whisker_protocol.h"

namespace whiskeye::sim {

struct TrueCalibration {
  std::array<wp::WhiskerCalibration, wp::kNumWhiskers> calibration{};
  std::array<int, wp::kNumWhiskers> channel{};  // whisker -> board channel (whiskerd's `channel`)
  std::array<int, 2> swapped{};                 // the two whiskers plugged into each other's sockets
  int mirrored_board = 0;                       // its whiskers' y axis is reversed (negative gain_y)
};

// Offsets ±150 counts, gains 0.8..1.25 × nominal, rotations ±0.35 rad, θ offsets ±80 counts, θ gains
// 0.9..1.1 × nominal; the same seed draws the same calibration.
TrueCalibration draw_true_calibration(uint64_t seed);

enum class Session { kRest, kTaps, kSweep, kJig };
// "rest", "taps", "sweep", "jig"; false for another name.
bool parse_session(const std::string& name, Session& session);

struct SessionParams {
  Session session = Session::kRest;
  double rate_hz = 500.0;                 // sample rate
  int64_t start_utime = 1700000000000000;
  uint64_t seed = 1;
  double noise = 0.003;                   // σ of each Hall axis, full scale (whiskerd's deflection units)
  std::vector<int> order;                 // taps, jig: the whiskers in the order touched (empty: 0..23)
  double rest_s = 5.0;                    // rest: length
  double tap_deflection = 0.3;            // taps: the largest push; each tap is 0.6..1 of it
  double jig_deflection = 0.5;            // jig: the deflection the jig applies, exactly
  double theta_stop = 60.0 * kPi / 180.0; // sweep: the end stops at ±this, rad (the joint range)
  double sweep_rate = 0.5;                // sweep: rad/s
  std::vector<int> stuck;                 // rest: whiskers whose Hall sensor reads one value
  int silent_board = -1;                  // a board that sends nothing (-1: none)
  double fault_at_s = -1.0;               // sweep: board 0 reports a fault from this time on (-1: never)
};

// The session's truth, per sample: θ and deflections as whiskerd should calibrate them.
using SessionSink = std::function<void(const rcp::WhiskerSample&, const WhiskerHealth&)>;
// Runs the session, calling `sink` for each sample (in time order). Returns the number of samples.
int64_t run_session(const SessionParams& params, const SessionSink& sink);

}  // namespace whiskeye::sim
