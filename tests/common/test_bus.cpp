#include "whiskeye/common/bus.h"

#include <whiskeye/pose2d_t.hpp>
#include <whiskeye/odometry_t.hpp>

#include <gtest/gtest.h>

#include <cstdio>

namespace whiskeye {
namespace {

TEST(MemoryBus, DeliversTypedMessagesToMatchingChannels) {
  MemoryBus bus;
  DecodeErrors errors;
  std::vector<double> got;
  subscribe<pose2d_t>(bus, "GROUND_.*", [&](const pose2d_t& m) { got.push_back(m.x); }, errors);
  pose2d_t p{};
  p.x = 1.5;
  publish(bus, "GROUND_TRUTH", p);
  publish(bus, "OTHER", p);
  ASSERT_EQ(got.size(), 1u);
  EXPECT_DOUBLE_EQ(got[0], 1.5);
  EXPECT_EQ(errors.total(), 0);
}

TEST(MemoryBus, CountsDecodeFailuresInsteadOfCrashing) {
  MemoryBus bus;
  DecodeErrors errors;
  std::string last_reason;
  errors.set_callback([&](const std::string&, const std::string& reason) { last_reason = reason; });
  int delivered = 0;
  subscribe<pose2d_t>(bus, "GROUND_TRUTH", [&](const pose2d_t&) { ++delivered; }, errors);

  odometry_t wrong_type{};
  publish(bus, "GROUND_TRUTH", wrong_type);  // fingerprint mismatch
  const std::vector<uint8_t> garbage{1, 2, 3};
  bus.publish_raw("GROUND_TRUTH", garbage);  // truncated
  std::vector<uint8_t> trailing = encode_message(pose2d_t{});
  trailing.push_back(0);
  bus.publish_raw("GROUND_TRUTH", trailing);

  EXPECT_EQ(delivered, 0);
  EXPECT_EQ(errors.total(), 3);
  EXPECT_EQ(errors.count("GROUND_TRUTH"), 3);
  EXPECT_NE(last_reason.find("trailing bytes"), std::string::npos);
  EXPECT_NE(last_reason.find("whiskeye.pose2d_t"), std::string::npos);
}

TEST(LogFiles, WriterAndReaderRoundTrip) {
  const std::string path = ::testing::TempDir() + "roundtrip.lcmlog";
  {
    LogWriterBus out(path);
    for (int i = 0; i < 5; ++i) {
      out.set_time(1000 + i);
      pose2d_t p{};
      p.utime = i;
      p.theta = 0.1 * i;
      publish(out, "GROUND_TRUTH", p);
    }
    EXPECT_EQ(out.events_written(), 5);
  }
  LogReader in(path);
  LogEvent ev;
  int n = 0;
  while (in.next(ev)) {
    pose2d_t p;
    ASSERT_TRUE(decode_message(ev.data, p));
    EXPECT_EQ(ev.channel, "GROUND_TRUTH");
    EXPECT_EQ(ev.utime, 1000 + n);
    EXPECT_EQ(p.utime, n);
    ++n;
  }
  EXPECT_EQ(n, 5);
  EXPECT_DOUBLE_EQ(in.progress(), 1.0);
  std::remove(path.c_str());
}

TEST(MemoryBus, PlainNamesMatchExactlyAndRegexesAsRegexes) {
  EXPECT_TRUE(is_plain_channel_name("WHISK_CYCLE"));
  EXPECT_FALSE(is_plain_channel_name("VITA_.*"));
  MemoryBus bus;
  DecodeErrors errors;
  int exact = 0;
  int regex = 0;
  subscribe<pose2d_t>(bus, "POSE", [&](const pose2d_t&) { ++exact; }, errors);
  subscribe<pose2d_t>(bus, "POSE|POSE_B", [&](const pose2d_t&) { ++regex; }, errors);
  publish(bus, "POSE", pose2d_t{});
  publish(bus, "POSE_B", pose2d_t{});
  publish(bus, "POSEX", pose2d_t{});
  EXPECT_EQ(exact, 1);
  EXPECT_EQ(regex, 2);
}

TEST(LogFiles, ViewsReadTheSameEventsWithoutCopying) {
  const std::string path = ::testing::TempDir() + "views.lcmlog";
  {
    LogWriterBus out(path);
    for (int i = 0; i < 3; ++i) {
      out.set_time(10 * i);
      pose2d_t p{};
      p.x = i;
      publish(out, i == 1 ? "B" : "A", p);
    }
  }
  LogReader in(path);
  LogReader::EventView ev;
  std::vector<std::string> channels;
  std::vector<double> xs;
  while (in.next(ev)) {
    pose2d_t p;
    ASSERT_TRUE(decode_message(ev.data, p));
    channels.emplace_back(ev.channel);
    xs.push_back(p.x);
    EXPECT_EQ(ev.utime, static_cast<int64_t>(10 * p.x));
  }
  EXPECT_EQ(channels, (std::vector<std::string>{"A", "B", "A"}));
  EXPECT_EQ(xs, (std::vector<double>{0, 1, 2}));
  std::remove(path.c_str());
}

TEST(LogFiles, MissingFileIsAnErrorNamingIt) {
  try {
    LogReader r("/nonexistent/x.lcmlog");
    FAIL();
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("/nonexistent/x.lcmlog"), std::string::npos);
  }
}

}  // namespace
}  // namespace whiskeye
