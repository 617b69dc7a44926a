// Unit tests of based's pure parts: health states and the burst log (health.h).
#include "whiskeye/based/health.h"

#include <gtest/gtest.h>

namespace whiskeye::based {
namespace {

TEST(BurstLog, LogsTheFirstFaultOfABurstAndItsCountWhenQuiet) {
  BurstLog log(1.0);
  EXPECT_NE(log.fault("reply_timeouts", "timed out", 0).find("reply_timeouts: timed out"), std::string::npos);
  EXPECT_EQ(log.fault("reply_timeouts", "timed out", 500'000), "");
  EXPECT_EQ(log.fault("reply_timeouts", "timed out", 1'400'000), "");  // still within 1 s of the last
  EXPECT_NE(log.fault("replies_malformed", "x", 1'400'000), "");      // another kind logs on its own
  EXPECT_TRUE(log.flush(2'000'000).empty());
  const std::vector<std::string> lines = log.flush(2'500'000);
  ASSERT_EQ(lines.size(), 1u);  // the single malformed reply needs no summary
  EXPECT_NE(lines[0].find("3 in total"), std::string::npos) << lines[0];
  EXPECT_NE(log.fault("reply_timeouts", "again", 3'000'000), "");  // a new burst logs again
}

TEST(Health, GoesFromStartingToOkAndDegradesOnFaults) {
  ConnectionParams c;
  c.fault_after_s = 2.0;
  c.degraded_hold_s = 1.0;
  OdometryParams o;
  o.stale_after_s = 0.5;
  Health h(c, o, 0);
  EXPECT_EQ(h.report(100'000).state, HealthState::kStarting);
  h.new_sample(200'000);
  EXPECT_EQ(h.report(210'000).state, HealthState::kOk);
  h.new_sample(300'000);
  h.fault("replies_malformed: bad", 300'000);
  Health::Report r = h.report(310'000);
  EXPECT_EQ(r.state, HealthState::kDegraded);
  EXPECT_EQ(r.message, "replies_malformed: bad");
  h.new_sample(1'350'000);
  EXPECT_EQ(h.report(1'360'000).state, HealthState::kOk);  // the fault is older than the hold
  r = h.report(2'000'000);                                   // no new sample for 0.65 s
  EXPECT_EQ(r.state, HealthState::kDegraded);
  EXPECT_NE(r.message.find("stale"), std::string::npos);
  r = h.report(3'500'000);
  EXPECT_EQ(r.state, HealthState::kFault);
  EXPECT_NE(r.message.find("no new odometry"), std::string::npos);
}

TEST(Health, UnreachableBaseIsDegradedThenFaultWithTheReason) {
  ConnectionParams c;
  c.fault_after_s = 1.0;
  Health h(c, OdometryParams{}, 0);
  h.reachable(false, "cannot connect to http://127.0.0.1:9: Connection", 100'000);
  EXPECT_EQ(h.report(200'000).state, HealthState::kStarting);
  const Health::Report r = h.report(1'200'000);
  EXPECT_EQ(r.state, HealthState::kFault);
  EXPECT_NE(r.message.find("cannot connect"), std::string::npos) << r.message;
  h.new_sample(1'300'000);
  EXPECT_EQ(h.report(1'310'000).state, HealthState::kDegraded);  // sample came, but still unreachable
  h.reachable(true, "", 1'320'000);
  EXPECT_EQ(h.report(1'330'000).state, HealthState::kDegraded);  // within the hold after the fault
}

}  // namespace
}  // namespace whiskeye::based
