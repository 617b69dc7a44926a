// Plain data types shared by the whisking controller, its plant model, whiskerd and vita-sim:
// one 500 Hz sample of all whiskers, the whisk phase, and one assembled whisk cycle.
// No LCM here; the daemons convert to and from whisker_sample_t / rcp_state_t / whisk_cycle_t.
#pragma once

#include <whiskeye/common/whisker_array.h>

#include <array>
#include <cstdint>
#include <vector>

namespace whiskeye::rcp {

// The array (common/whisker_array.h). Whisker index w = row * kWhiskerColumns + column (rows top to
// bottom, columns front to back).
using whiskeye::kNumWhiskers;
using whiskeye::kWhiskerColumns;
using whiskeye::kWhiskerRows;

constexpr int row_of(int whisker) { return whisker / kWhiskerColumns; }
constexpr int column_of(int whisker) { return whisker % kWhiskerColumns; }
constexpr int whisker_index(int row, int column) { return row * kWhiskerColumns + column; }

template <typename T>
using PerWhisker = std::array<T, kNumWhiskers>;

// One sample of all whiskers. theta in rad (+ = protraction); deflection calibrated and
// dimensionless, |(x, y)| roughly 0..1 of the Hall sensor's full scale. A whisker whose value is
// stale or faulty this period has valid[w] = false; the controller then holds its state.
struct WhiskerSample {
  int64_t utime = 0;  // sample time, microseconds
  int64_t seq = 0;    // +1 per sample; a jump means samples were lost
  PerWhisker<double> theta{};
  PerWhisker<double> deflection_x{};
  PerWhisker<double> deflection_y{};
  PerWhisker<bool> valid{};
};

// Values match rcp_state_t.PHASE_* (0, 1, 2).
enum class Phase : int8_t { Protract = 0, Retract = 1, Rest = 2 };

const char* to_string(Phase phase);

// Every sample of one whisk cycle (protraction + retraction), the input of slamd's tactile
// template. Samples lost on the bus are present with valid = false and zero values at their
// expected times; they are never interpolated. In a measured sample, a whisker that was not (its
// board stale or faulty that period) has NaN theta and deflections.
struct WhiskCycle {
  int64_t cycle = 0;        // whisk cycle number (+1 at each cycle start)
  int64_t utime_start = 0;  // time of the first sample (measured or missing) of the cycle
  int64_t utime_end = 0;    // time of the last sample of the cycle
  struct Sample {
    int64_t utime = 0;
    bool valid = false;  // false: lost sample (sequence gap), all values zero
    Phase phase = Phase::Protract;
    std::array<float, kNumWhiskers> theta{};
    std::array<float, kNumWhiskers> deflection_x{};
    std::array<float, kNumWhiskers> deflection_y{};
    std::array<bool, kNumWhiskers> contact{};  // contact detector output (hysteresis state)
  };
  std::vector<Sample> samples;
  int num_missing = 0;  // samples with valid = false
};

}  // namespace whiskeye::rcp
