// LCM time stamps: int64 microseconds since the epoch, the time the data was sampled.
// Pure conversions here; reading the clock lives in clock.h (daemons only).
#pragma once

#include <cmath>
#include <cstdint>

namespace whiskeye {

constexpr int64_t kUtimePerSecond = 1'000'000;

inline double utime_to_seconds(int64_t utime) { return static_cast<double>(utime) * 1e-6; }

// Rounds to the nearest microsecond.
inline int64_t seconds_to_utime(double seconds) { return std::llround(seconds * 1e6); }

// Difference b - a in seconds.
inline double utime_delta_seconds(int64_t a, int64_t b) { return static_cast<double>(b - a) * 1e-6; }

}  // namespace whiskeye
