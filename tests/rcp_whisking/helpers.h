// Small builders shared by the rcp_whisking tests.
#pragma once

#include <whiskeye/rcp/rcp.h>

namespace whiskeye::rcp::test {

constexpr int64_t kPeriodUs = 2000;      // 500 Hz
constexpr int64_t kStartUtime = 5'000'000;

// A sample with every whisker valid, deflection (x, y) on all of them, theta = 0.
inline WhiskerSample make_sample(int64_t seq, double x = 0.0, double y = 0.0) {
  WhiskerSample s;
  s.seq = seq;
  s.utime = kStartUtime + seq * kPeriodUs;
  s.deflection_x.fill(x);
  s.deflection_y.fill(y);
  s.valid.fill(true);
  return s;
}

}  // namespace whiskeye::rcp::test
