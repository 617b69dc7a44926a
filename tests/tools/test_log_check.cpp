// whiskeye-logcheck's analysis (tools/logcheck): sequence gaps, restarts, rates and pauses.
#include "whiskeye/logcheck/log_check.h"

#include "whiskeye/common/bus.h"

#include <whiskeye/image_t.hpp>
#include <whiskeye/odometry_t.hpp>
#include <whiskeye/pose2d_t.hpp>
#include <whiskeye/whisk_cycle_t.hpp>
#include <whiskeye/whisker_sample_t.hpp>

#include <gtest/gtest.h>

#include <limits>

namespace whiskeye::logcheck {
namespace {

template <typename T>
std::vector<uint8_t> bytes(const T& msg) {
  return encode_message(msg);
}

std::vector<uint8_t> sample(int64_t seq) {
  constexpr std::size_t kWhiskers = 24;
  whisker_sample_t m{};
  m.utime = 1'000'000 + seq * 2000;
  m.seq = seq;
  m.num_whiskers = kWhiskers;
  m.theta = m.deflection_x = m.deflection_y = std::vector<float>(kWhiskers, 0.0f);
  m.raw_x = m.raw_y = m.raw_theta = std::vector<int16_t>(kWhiskers, 0);
  m.status = std::vector<int8_t>(kWhiskers, 0);
  return bytes(m);
}

TEST(LogCheck, CountsMessagesMissingFromTheSequenceAndWhereTheyWent) {
  LogCheck check;
  for (int64_t seq : {1, 2, 3, 7, 8, 9, 10, 12}) check.add("WHISKER_SAMPLE", 1'000'000 + seq * 2000, sample(seq));
  const auto channels = check.channels();
  ASSERT_EQ(channels.size(), 1u);
  const ChannelStats& s = channels[0];
  EXPECT_TRUE(s.sequenced);
  EXPECT_EQ(s.count, 8);
  EXPECT_EQ(s.lost, 4);  // 4, 5, 6 and 11
  EXPECT_EQ(s.loss_places, 2);
  EXPECT_EQ(s.longest_loss, 3);
  EXPECT_EQ(s.restarts, 0);
  EXPECT_DOUBLE_EQ(s.lost_fraction(), 4.0 / 12.0);
}

TEST(LogCheck, ASenderThatStartsAgainIsARestartNotALoss) {
  LogCheck check;
  for (int64_t seq : {100, 101, 102, 0, 1, 2}) check.add("WHISKER_SAMPLE", 0, sample(seq));
  const ChannelStats s = check.channels().at(0);
  EXPECT_EQ(s.lost, 0);
  EXPECT_EQ(s.restarts, 1);
}

TEST(LogCheck, AChannelWithoutSequenceNumbersGetsItsRateAndPausesOnly) {
  LogCheck check(3.0);
  pose2d_t pose{};
  const auto data = bytes(pose);
  // 10 Hz for 2 s, a 1 s pause, 10 Hz again.
  int64_t t = 0;
  for (int i = 0; i < 20; ++i) check.add("VITA_POSE", t += 100'000, data);
  t += 900'000;
  for (int i = 0; i < 20; ++i) check.add("VITA_POSE", t += 100'000, data);
  const ChannelStats s = check.channels().at(0);
  EXPECT_FALSE(s.sequenced);
  EXPECT_EQ(s.lost, 0);
  EXPECT_EQ(s.count, 40);
  EXPECT_EQ(s.time_gaps, 1);
  EXPECT_EQ(s.max_interval_us, 1'000'000);
  EXPECT_NEAR(s.rate_hz(), 39.0 / 4.8, 1e-9);
}

// ODOMETRY seq −2^63 then 2^63 − 1: the loss saturates at int64's largest; the messages sent (2 + it)
// are beyond int64, and were "of −9223372036854775807 (0.00 %)", which passed --max-loss 0.
TEST(LogCheck, ALossAcrossTheWholeInt64RangeIsNearlyAllTheMessagesAndFailsAnyMaxLoss) {
  constexpr int64_t kMin = std::numeric_limits<int64_t>::min();
  constexpr int64_t kMax = std::numeric_limits<int64_t>::max();
  LogCheck check;
  odometry_t odo{};
  odo.seq = kMin;
  check.add("ODOMETRY", 1'000'000, bytes(odo));
  odo.seq = kMax;
  check.add("ODOMETRY", 1'020'000, bytes(odo));
  const ChannelStats s = check.channels().at(0);
  ASSERT_TRUE(s.sequenced);
  EXPECT_EQ(s.lost, kMax);
  EXPECT_EQ(s.sent(), 9223372036854775809ull);
  EXPECT_DOUBLE_EQ(s.lost_fraction(), 1.0);
  EXPECT_TRUE(s.lost_more_than(0.0));
  EXPECT_TRUE(s.lost_more_than(0.5));
  EXPECT_FALSE(s.lost_more_than(1.0));
}

TEST(LogCheck, AnyLossIsMoreThanNoneAndNoLossIsMoreThanNothing) {
  LogCheck check;
  for (int64_t seq : {1, 3}) check.add("WHISKER_SAMPLE", 0, sample(seq));
  check.add("VITA_POSE", 0, bytes(pose2d_t{}));
  const auto channels = check.channels();
  EXPECT_FALSE(channels.at(0).lost_more_than(0.0));  // VITA_POSE: no sequence numbers
  EXPECT_TRUE(channels.at(1).lost_more_than(0.0));   // WHISKER_SAMPLE: 1 of 3
  EXPECT_FALSE(channels.at(1).lost_more_than(0.5));
}

TEST(LogCheck, TimesAcrossTheWholeInt64RangeGiveASmallPositiveRateAndASaturatedPause) {
  LogCheck check;
  pose2d_t pose{};
  const auto data = bytes(pose);
  constexpr int64_t kMin = std::numeric_limits<int64_t>::min();
  constexpr int64_t kMax = std::numeric_limits<int64_t>::max();
  check.add("VITA_POSE", kMin, data);
  check.add("VITA_POSE", kMax, data);
  check.add("VITA_POSE", kMin, data);  // and back: an interval below int64
  const ChannelStats s = check.channels().at(0);
  EXPECT_EQ(s.max_interval_us, kMax);
  EXPECT_GT(s.rate_hz(), 0.0);
  EXPECT_NEAR(s.rate_hz(), 2.0 * 1e6 / 18446744073709551615.0, 1e-20);  // two intervals over 2^64 − 1 µs
}

TEST(LogCheck, AClockThatJumpsBackRatesTheEventsOverTheTimesTheyCover) {
  LogCheck check;
  pose2d_t pose{};
  const auto data = bytes(pose);
  for (int64_t t : {5'000'000, 6'000'000, 1'000'000, 2'000'000, 3'000'000}) check.add("VITA_POSE", t, data);
  EXPECT_NEAR(check.channels().at(0).rate_hz(), 4.0 / 5.0, 1e-12);  // 5 events over 1..6 s
}

TEST(LogCheck, ChannelsComeOutByName) {
  LogCheck check;
  check.add("ODOMETRY", 0, sample(1));
  check.add("CAMERA", 0, sample(1));
  const auto channels = check.channels();
  ASSERT_EQ(channels.size(), 2u);
  EXPECT_EQ(channels[0].channel, "CAMERA");
  EXPECT_EQ(channels[1].channel, "ODOMETRY");
}

}  // namespace
}  // namespace whiskeye::logcheck
