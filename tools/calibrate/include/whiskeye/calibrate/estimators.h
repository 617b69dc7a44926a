// whiskeye-calibrate's estimators (docs/bring-up.md): the bus check, and the calibration whiskerd
// needs from a rest recording (offsets, noise), a tap test (wiring, axis orientation), jig
// deflections (gains, rotation) and a θ sweep between the end stops (θ offset and gain); whiskerd's
// plausibility bounds checked; the drop-in entries and the old/new table. Pure: a Recording and whiskerd's calibration
// in use in, plain data out.
#pragma once

#include <whiskeye/common/se2.h>

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "whiskeye/calibrate/recording.h"
#include "whiskeye/whiskerd/config.h"

namespace whiskeye::calibrate {

// One value estimated: the whisker, its whiskerd.yaml key, the value in use, the new one and its
// 1-sigma uncertainty (0: exact, e.g. a channel).
struct Estimate {
  int whisker = 0;
  std::string key;
  double old_value = 0, new_value = 0, uncertainty = 0;
};

// What was wrong with the input, one line each; any problem means nothing is written.
using Problems = std::vector<std::string>;

struct Result {
  std::vector<Estimate> estimates;
  Problems problems;
};

// ---- bus
struct BoardVerdict {
  int board = 0;
  bool ok = false;
  double sample_hz = 0, heartbeat_hz = 0;
  int64_t gaps = 0;
  std::string reason;  // why not ok ("" if ok)
};
struct BusReport {
  std::array<BoardVerdict, wp::kNumBoards> boards{};
  double load = 0, expected_load = 0;  // busy fraction of the bus: heard, and wp::bus_load() (commands included)
  int64_t error_frames = 0, rejected = 0;
  bool ok = false;
};
// Every board present, its sample rate within 5 % of rate_hz, heartbeats within 30 % of
// wp::kHeartbeatHz, operational, no gap over 0.1 % of its samples, no fault; no error frame, no
// rejected frame, the load within wp::bus_load()'s figure. `duration_s`: how long was listened.
BusReport check_bus(const Recording& r, double rate_hz, double duration_s);
std::string format_bus_report(const BusReport& report);

// ---- plausibility: whiskerd's own bounds (whiskerd::kCalibrationBounds, which its loader enforces):
// an estimate outside them is refused, never written
Problems check_bounds(const std::vector<Estimate>& estimates);

// ---- rest: offsets and noise; refuses a silent board, a recording too short to estimate them, a
// stuck, saturated, faulty or noisy sensor
struct RestLimits {
  double max_noise_counts = 40;  // a sensor noisier than this is refused
  // Samples per board, at least: the noise (and so the stuck check and the offsets' ±) needs two;
  // 100 (0.2 s at 500 Hz, 1 s at 100 Hz) give an offset to a tenth of the noise.
  int64_t min_samples = 100;
};
Result estimate_rest(const Recording& r, const whiskerd::CoreParams& current, const RestLimits& limits);

// ---- pushes: a whisker pushed and released (a tap, a jig), found in a recording
struct Push {
  int channel = 0;
  int64_t start_utime = 0, end_utime = 0;
  double dx = 0, dy = 0;  // mean displacement from the channel's rest over the push's plateau, counts
  double sigma = 0;       // uncertainty of that mean, counts
};
// Every push in time order: a channel that leaves its rest (median) by more than 10 sigma (at least
// 30 counts) for 50 ms or more, until 10 samples in a row are back at rest. Pushes of two channels at once: the larger one (the other is crosstalk).
std::vector<Push> find_pushes(const Recording& r);

// The whiskers of `order`, each pushed forward (+x) then up (+y): which channel each is on, its
// rotation and the signs of its gains (a mirrored board), with |gain| kept. An empty `order`: 0..23.
Result map_whiskers(const std::vector<Push>& pushes, const std::vector<int>& order, const whiskerd::CoreParams& current);
// The same pushes by a jig of known `deflection` (whiskerd's units): gain_x, gain_y and rotation.
// The channels must be those whiskerd wires (map first).
Result fit_gains(const std::vector<Push>& pushes, const std::vector<int>& order, double deflection,
                 const whiskerd::CoreParams& current);
// θ swept through the joint range against both end stops at ±stop_rad: theta_offset (the stops'
// midpoint) and theta_gain. A fault during the sweep, or a stop not reached, is a problem.
Result fit_theta(const Recording& r, double stop_rad, const whiskerd::CoreParams& current);

// ---- output
// The drop-in's entries: every estimated key, per whisker in index order.
std::vector<whiskerd::CalibrationEntry> dropin_entries(const std::vector<Estimate>& estimates);
// "whisker  key  old  new  ±" lines.
std::string format_table(const std::vector<Estimate>& estimates);
// "whisker 9 (row 1, column 3)".
std::string whisker_name(int w);

}  // namespace whiskeye::calibrate
