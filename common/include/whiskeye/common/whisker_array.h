// The WhiskEye's whisker array, defined once for every module that counts whiskers: the geometry
// (robot_geometry.h), the whisking controller (rcp), the CAN protocol (whisker_protocol) and the
// simulator take these; none defines its own. Likewise the rate the array is sampled and controlled at.
//   24 whiskers in 4 rows of 6; whisker w = row * 6 + column (rows top to bottom).
//   6 whisker boards of 4 whiskers on the CAN bus (docs/can-protocol.md gives the wiring).
#pragma once

#include <cstdint>

namespace whiskeye {

inline constexpr int kWhiskerRows = 4;
inline constexpr int kWhiskerColumns = 6;
inline constexpr int kNumWhiskers = kWhiskerRows * kWhiskerColumns;

inline constexpr int kNumBoards = 6;         // whisker boards on the CAN bus
inline constexpr int kWhiskersPerBoard = 4;  // whiskers read and driven by one board
static_assert(kNumBoards * kWhiskersPerBoard == kNumWhiskers, "every whisker is on one board");

// How often the boards sample and the whisking controller steps, unless configured otherwise
// (whiskerd.yaml's can.rate_hz: 500 Hz over CAN FD; docs/can-protocol.md).
inline constexpr double kControlRateHz = 500.0;
inline constexpr int64_t kControlPeriodUs = 2000;
static_assert(kControlPeriodUs * kControlRateHz == 1e6, "the period is the rate's");

}  // namespace whiskeye
