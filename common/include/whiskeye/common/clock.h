// Wall-clock and monotonic time for daemons. Algorithm code never includes this: time is an argument.
#pragma once

#include <chrono>
#include <cstdint>

namespace whiskeye {

// Microseconds since the epoch (CLOCK_REALTIME), the LCM utime convention.
inline int64_t now_utime() {
  return std::chrono::duration_cast<std::chrono::microseconds>(
             std::chrono::system_clock::now().time_since_epoch())
      .count();
}

// Microseconds of CLOCK_MONOTONIC, for measuring latencies and deadlines.
inline int64_t monotonic_us() {
  return std::chrono::duration_cast<std::chrono::microseconds>(
             std::chrono::steady_clock::now().time_since_epoch())
      .count();
}

}  // namespace whiskeye
