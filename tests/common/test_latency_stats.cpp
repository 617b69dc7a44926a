// Latency statistics per reporting interval (latency_stats.h).

#include <gtest/gtest.h>

#include "whiskeye/common/latency_stats.h"

using namespace whiskeye;

TEST(LatencyStats, ReportsPercentilesAndMaxPerInterval) {
  LatencyStats s(1000);
  for (int i = 1; i <= 100; ++i) s.add(i);
  const LatencySummary a = s.take();
  EXPECT_EQ(a.count, 100);
  EXPECT_EQ(a.max_us, 100);
  EXPECT_NEAR(a.p50_us, 51, 1);
  EXPECT_NEAR(a.p99_us, 100, 1);
  EXPECT_EQ(s.take().count, 0);
}
