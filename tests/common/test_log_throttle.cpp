// The rate limit for repeated log lines (common/log_throttle.h).
#include "whiskeye/common/log_throttle.h"

#include <gtest/gtest.h>

namespace whiskeye {
namespace {

constexpr int64_t kS = 1'000'000;

TEST(LogThrottle, LogsTheFirstLineThenOnePerPeriodSayingHowManyWereSuppressed) {
  LogThrottle t(10 * kS);
  EXPECT_EQ(t.admit("decode", "bad 1", 0), "bad 1");
  int logged = 0;
  for (int i = 2; i <= 2000; ++i) logged += t.admit("decode", "bad", i * 1000).has_value();
  EXPECT_EQ(logged, 0) << "2,000 lines in 2 s: only the first";
  EXPECT_EQ(t.suppressed("decode"), 1999);
  EXPECT_EQ(t.admit("decode", "bad 2001", 10 * kS), "bad 2001; 1999 more like it suppressed in the last 10 s");
  EXPECT_EQ(t.suppressed("decode"), 0);
  EXPECT_FALSE(t.admit("decode", "bad", 11 * kS));
}

TEST(LogThrottle, KeysAreLimitedSeparately) {
  LogThrottle t(10 * kS);
  EXPECT_TRUE(t.admit("decode CAMERA", "a", 0));
  EXPECT_TRUE(t.admit("decode ODOMETRY", "b", 1));
  EXPECT_FALSE(t.admit("decode CAMERA", "a", 2));
}

TEST(LogThrottle, AForcedLineCarriesTheCountAndRestartsThePeriod) {
  LogThrottle t(10 * kS);
  t.admit("k", "x", 0);
  t.admit("k", "x", 1);
  EXPECT_EQ(t.force("k", "new burst", 2), "new burst; 1 more like it suppressed in the last 0 s");
  EXPECT_FALSE(t.admit("k", "x", 3));
}

TEST(LogThrottle, AClockThatWentBackDoesNotMuteAKey) {
  LogThrottle t(10 * kS);
  t.admit("k", "x", 100 * kS);
  EXPECT_TRUE(t.admit("k", "x", 5 * kS));
}

}  // namespace
}  // namespace whiskeye
