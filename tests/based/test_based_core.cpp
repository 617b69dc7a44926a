// Unit tests of based's pure parts: protocol bodies, sequence/jump tracking, health, deadman and
// limits, the circle trajectory, parameters.
#include "whiskeye/based/circle.h"
#include "whiskeye/based/health.h"
#include "whiskeye/based/motion.h"
#include "whiskeye/based/params.h"
#include "whiskeye/based/protocol.h"
#include "whiskeye/based/tracker.h"
#include "whiskeye/common/se2.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <cmath>
#include <limits>

namespace whiskeye::based {
namespace {

// ---- protocol ----

TEST(OdometryReply, ParsesTheSevenElementArray) {
  OdometrySample s;
  std::string error;
  ASSERT_TRUE(parse_odometry_reply("[1.5, -2.25, 3.0, 0.1, -0.2, 0.3, 42]", s, error)) << error;
  EXPECT_DOUBLE_EQ(s.x, 1.5);
  EXPECT_DOUBLE_EQ(s.y, -2.25);
  EXPECT_DOUBLE_EQ(s.theta, 3.0);
  EXPECT_DOUBLE_EQ(s.vx, 0.1);
  EXPECT_DOUBLE_EQ(s.vy, -0.2);
  EXPECT_DOUBLE_EQ(s.omega, 0.3);
  EXPECT_EQ(s.seq, 42);
}

TEST(OdometryReply, AcceptsSeqWrittenAsAnIntegralFloat) {
  OdometrySample s;
  std::string error;
  ASSERT_TRUE(parse_odometry_reply(" [0,0,0,0,0,0,12.0]\n", s, error)) << error;
  EXPECT_EQ(s.seq, 12);
}

struct BadReply {
  const char* body;
  const char* says;
};

class RejectsBadReply : public ::testing::TestWithParam<BadReply> {};

TEST_P(RejectsBadReply, WithAReasonNamingTheProblem) {
  OdometrySample s;
  s.x = 99.0;
  std::string error;
  EXPECT_FALSE(parse_odometry_reply(GetParam().body, s, error));
  EXPECT_NE(error.find(GetParam().says), std::string::npos) << error;
  EXPECT_EQ(s.x, 99.0) << "a rejected reply must not change the sample";
}

INSTANTIATE_TEST_SUITE_P(
    OdometryReply, RejectsBadReply,
    ::testing::Values(BadReply{"", "not JSON"}, BadReply{"[1, 2, oops", "not JSON"},
                      BadReply{"[NaN, 0, 0, 0, 0, 0, 1]", "not JSON"},
                      BadReply{"[1e999, 0, 0, 0, 0, 0, 1]", "not"},
                      BadReply{"{\"x\": 1}", "not a JSON array"},
                      BadReply{"[1.0, 2.0, 3.0]", "has 3 elements"},
                      BadReply{"[0,0,0,0,0,0,1,2]", "has 8 elements"},
                      BadReply{"[0, 0, null, 0, 0, 0, 1]", "rot is not a number"},
                      BadReply{"[0, \"1\", 0, 0, 0, 0, 1]", "y is not a number"},
                      BadReply{"[0, 0, 0, 0, 0, 0, 1.5]", "seq is not a non-negative integer"},
                      BadReply{"[0, 0, 0, 0, 0, 0, -3]", "seq is negative"},
                      BadReply{"[0, 0, 0, 0, 0, 0, 18446744073709551615]", "seq is negative or too large"},
                      // Finite but impossible (found by fuzzing): each left ODOMETRY wrong until a restart.
                      BadReply{"[1.7976931348623157e308, 0, 0, 0, 0, 0, 1]", "element x = 1.7976931348623157e+308 is beyond"},
                      BadReply{"[0, 1e20, 1, 0.2, 0, 0.1, 1]", "element y = 1e+20 is beyond any base's (100000.0)"},
                      BadReply{"[0, 0, 1e17, 0.2, 0, 0.1, 1]", "element rot = 1e+17 is beyond"},
                      BadReply{"[0.5, 0.5, 0, 1e300, 0, 0, 1]", "element vx = 1e+300 is beyond"},
                      BadReply{"[0, 0, 0, 0, 0, 5000, 1]", "element omega = 5000.0 is beyond"},
                      BadReply{"[0, \"0123456789012345678901234567890123456789xyz\", 0, 0, 0, 0, 1]",
                               "y is not a number: \"0123456789012345678901234567890123456789\"..."}));

// A reply nested 100,000 deep in an element: the error line describes it by its size (dumping it
// recursed once per level and overflowed the poll thread's stack, killing based).
TEST(OdometryReply, ADeeplyNestedElementIsRejectedWithoutRecursing) {
  const std::string deep = "[" + std::string(100000, '[') + std::string(100000, ']') + ",0,0,0,0,0,0]";
  OdometrySample s;
  std::string error;
  EXPECT_FALSE(parse_odometry_reply(deep, s, error));
  EXPECT_NE(error.find("odometry reply of 200014 bytes, more than 4 KiB"), std::string::npos) << error;
  const std::string nested = "[" + std::string(1000, '[') + std::string(1000, ']') + ",0,0,0,0,0,0]";
  EXPECT_FALSE(parse_odometry_reply(nested, s, error));
  EXPECT_NE(error.find("element x is not a number: a JSON array of 1 elements"), std::string::npos) << error;
}

TEST(OmnidriveCommand, IsAJsonArrayOfThreeNumbersThatRoundTrips) {
  const std::string body = format_omnidrive_command(0.25, -0.125, 1.0 / 3.0);
  const nlohmann::json j = nlohmann::json::parse(body);
  ASSERT_TRUE(j.is_array());
  ASSERT_EQ(j.size(), 3u);
  EXPECT_EQ(j[0].get<double>(), 0.25);
  EXPECT_EQ(j[1].get<double>(), -0.125);
  EXPECT_EQ(j[2].get<double>(), 1.0 / 3.0);
}

TEST(BaseUrl, ParsesHostAndPort) {
  BaseUrl u;
  std::string error;
  ASSERT_TRUE(parse_base_url("http://192.168.0.1:80", u, error)) << error;
  EXPECT_EQ(u.host, "192.168.0.1");
  EXPECT_EQ(u.port, 80);
  ASSERT_TRUE(parse_base_url("http://robotino/", u, error)) << error;
  EXPECT_EQ(u.host, "robotino");
  EXPECT_EQ(u.port, 80);
  ASSERT_TRUE(parse_base_url("http://127.0.0.1:8080", u, error));
  EXPECT_EQ(u.port, 8080);
}

TEST(BaseUrl, RejectsWhatItCannotUse) {
  BaseUrl u;
  std::string error;
  EXPECT_FALSE(parse_base_url("https://base", u, error));
  EXPECT_NE(error.find("http://"), std::string::npos);
  EXPECT_FALSE(parse_base_url("http://base:0", u, error));
  EXPECT_NE(error.find("bad port"), std::string::npos);
  EXPECT_FALSE(parse_base_url("http://base:99999", u, error));
  EXPECT_FALSE(parse_base_url("http://base:8x", u, error));
  EXPECT_FALSE(parse_base_url("http://:80", u, error));
  EXPECT_NE(error.find("no host"), std::string::npos);
  EXPECT_FALSE(parse_base_url("http://base/data/odometry", u, error));
  EXPECT_NE(error.find("without a path"), std::string::npos);
}

TEST(SampleUtime, IsTheMiddleOfTheRoundTrip) {
  EXPECT_EQ(sample_utime(1'000'000, 20'000), 990'000);
  EXPECT_EQ(sample_utime(1'000'000, 0), 1'000'000);
}

// ---- tracker ----

OdometrySample sample(int64_t seq, int64_t utime, double x, double y, double theta, double vx = 0.0,
                      double vy = 0.0, double omega = 0.0) {
  OdometrySample s;
  s.seq = seq;
  s.utime = utime;
  s.mono_us = utime;  // the clocks agree unless a test steps the wall clock
  s.x = x;
  s.y = y;
  s.theta = theta;
  s.vx = vx;
  s.vy = vy;
  s.omega = omega;
  return s;
}

TEST(OdometryTracker, PublishesFirstAndNewSamplesWithThetaWrapped) {
  OdometryTracker t{OdometryParams{}};
  TrackResult r = t.track(sample(10, 1'000'000, 1.0, 2.0, 3.1, 0.1, 0.0, 0.5));
  EXPECT_EQ(r.kind, SampleKind::kFirst);
  ASSERT_TRUE(r.publish);
  EXPECT_DOUBLE_EQ(r.publish->x, 1.0);
  r = t.track(sample(11, 1'020'000, 1.002, 2.0, 3.15, 0.1, 0.0, 0.5));
  EXPECT_EQ(r.kind, SampleKind::kNew);
  ASSERT_TRUE(r.publish);
  EXPECT_NEAR(r.publish->theta, 3.15 - kTwoPi, 1e-12);
  EXPECT_EQ(r.publish->seq, 11);
  EXPECT_EQ(r.publish->utime, 1'020'000);
  EXPECT_DOUBLE_EQ(r.publish->vx, 0.1);
}

TEST(OdometryTracker, DoesNotPublishARepeatedSeq) {
  OdometryTracker t{OdometryParams{}};
  t.track(sample(10, 1'000'000, 0, 0, 0));
  const TrackResult r = t.track(sample(10, 1'020'000, 0, 0, 0));
  EXPECT_EQ(r.kind, SampleKind::kRepeated);
  EXPECT_FALSE(r.publish);
  EXPECT_NE(r.detail.find("seq 10"), std::string::npos);
  EXPECT_EQ(t.last_new_utime(), 1'000'000);
}

TEST(OdometryTracker, SeqGoingBackwardsIsAReset) {
  OdometryTracker t{OdometryParams{}};
  t.track(sample(10, 1'000'000, 0, 0, 0));
  const TrackResult r = t.track(sample(3, 1'020'000, 0, 0, 0));
  EXPECT_EQ(r.kind, SampleKind::kSeqBackwards);
  EXPECT_TRUE(r.publish);
}

TEST(OdometryTracker, FastButExplainedMotionIsNotAJump) {
  OdometryTracker t{OdometryParams{}};
  // 1 m/s for 0.5 s (replies were lost in between): 0.5 m is what the velocity explains.
  t.track(sample(10, 1'000'000, 0, 0, 0, 1.0, 0.0, 2.0));
  const TrackResult r = t.track(sample(35, 1'500'000, 0.5, 0.0, 1.0, 1.0, 0.0, 2.0));
  EXPECT_EQ(r.kind, SampleKind::kNew) << r.detail;
}

TEST(OdometryTracker, PositionOrHeadingJumpBeyondVelocityIsAReset) {
  OdometryTracker t{OdometryParams{}};
  t.track(sample(10, 1'000'000, 3.0, 1.0, 0.5, 0.2, 0.0, 0.0));
  TrackResult r = t.track(sample(11, 1'020'000, 0.0, 0.0, 0.0, 0.2, 0.0, 0.0));  // base zeroed its odometry
  EXPECT_EQ(r.kind, SampleKind::kJump);
  EXPECT_NE(r.detail.find("jumped"), std::string::npos);

  OdometryTracker h{OdometryParams{}};
  h.track(sample(10, 1'000'000, 0, 0, 3.1));
  r = h.track(sample(11, 1'020'000, 0, 0, -3.1));  // across ±pi: only 0.08 rad, not a jump
  EXPECT_EQ(r.kind, SampleKind::kNew);
  r = h.track(sample(12, 1'040'000, 0, 0, -2.5));
  EXPECT_EQ(r.kind, SampleKind::kJump);
}

TEST(OdometryTracker, KeepsPublishedPoseContinuousAfterAReset) {
  OdometryTracker t{OdometryParams{}};
  const double vx = 0.2, omega = 0.4;
  TrackResult r = t.track(sample(10, 1'000'000, 3.0, 1.0, 0.5, vx, 0.0, omega));
  r = t.track(sample(11, 1'020'000, 0.0, 0.0, 0.0, vx, 0.0, omega));  // reset to the origin
  ASSERT_EQ(r.kind, SampleKind::kJump);
  const Pose2 predicted = integrate_body_velocity(Pose2{3.0, 1.0, 0.5}, vx, 0.0, omega, 0.02);
  EXPECT_NEAR(r.publish->x, predicted.x, 1e-12);
  EXPECT_NEAR(r.publish->y, predicted.y, 1e-12);
  EXPECT_NEAR(r.publish->theta, predicted.theta, 1e-12);
  // Later motion in the base's new frame carries over, rotated into the published frame.
  const Pose2 step = integrate_body_velocity(Pose2{0, 0, 0}, vx, 0.0, omega, 0.02);
  r = t.track(sample(12, 1'040'000, step.x, step.y, step.theta, vx, 0.0, omega));
  ASSERT_EQ(r.kind, SampleKind::kNew);
  const Pose2 expected = compose(predicted, step);
  EXPECT_NEAR(r.publish->x, expected.x, 1e-12);
  EXPECT_NEAR(r.publish->y, expected.y, 1e-12);
  EXPECT_NEAR(r.publish->theta, expected.theta, 1e-12);
}

TEST(OdometryTracker, PassesTheNewOriginThroughWhenAskedTo) {
  OdometryParams p;
  p.continuous_after_reset = false;
  OdometryTracker t{p};
  t.track(sample(10, 1'000'000, 3.0, 1.0, 0.5));
  const TrackResult r = t.track(sample(11, 1'020'000, 0.0, 0.0, 0.0));
  ASSERT_EQ(r.kind, SampleKind::kJump);
  EXPECT_EQ(r.publish->x, 0.0);
  EXPECT_EQ(r.publish->theta, 0.0);
}

// The wall clock steps (NTP); the monotonic clock does not. The checks must follow the monotonic one.
OdometrySample with_wall_clock(OdometrySample s, int64_t utime) {
  s.utime = utime;
  return s;
}

TEST(OdometryTracker, WallClockStepBackDoesNotMakeNormalMotionAJump) {
  OdometryTracker t{OdometryParams{}};
  // 1 m/s and 1.5 rad/s, two samples 0.1 s apart (replies lost in between): 0.1 m and 0.15 rad are
  // explained by the velocity. The wall clock is stepped back 5 s between them.
  t.track(with_wall_clock(sample(10, 1'000'000, 0.0, 0.0, 0.0, 1.0, 0.0, 1.5), 1'700'000'005'000'000));
  const TrackResult r =
      t.track(with_wall_clock(sample(15, 1'100'000, 0.1, 0.0, 0.15, 1.0, 0.0, 1.5), 1'700'000'000'100'000));
  EXPECT_EQ(r.kind, SampleKind::kNew) << r.detail;
  ASSERT_TRUE(r.publish);
  EXPECT_EQ(r.publish->utime, 1'700'000'000'100'000);  // published with its wall-clock time all the same
}

TEST(OdometryTracker, WallClockStepForwardDoesNotHideAJump) {
  OdometryTracker t{OdometryParams{}};
  const double vx = 0.2, omega = 0.4;
  t.track(with_wall_clock(sample(10, 1'000'000, 3.0, 1.0, 0.5, vx, 0.0, omega), 1'700'000'000'000'000));
  // The base zeroes its odometry 20 ms later; meanwhile the wall clock jumped 1 h ahead.
  const TrackResult r =
      t.track(with_wall_clock(sample(11, 1'020'000, 0.0, 0.0, 0.0, vx, 0.0, omega), 1'700'003'600'020'000));
  ASSERT_EQ(r.kind, SampleKind::kJump);
  EXPECT_NE(r.detail.find("in 0.02 s"), std::string::npos) << r.detail;
  // Re-anchored on the 20 ms the base really moved, not on an hour (clamped to 1 s) of wall clock.
  const Pose2 predicted = integrate_body_velocity(Pose2{3.0, 1.0, 0.5}, vx, 0.0, omega, 0.02);
  EXPECT_NEAR(r.publish->x, predicted.x, 1e-12);
  EXPECT_NEAR(r.publish->y, predicted.y, 1e-12);
  EXPECT_NEAR(r.publish->theta, predicted.theta, 1e-12);
}

TEST(OdometryTracker, StaleFollowsTheMonotonicClock) {
  OdometryParams p;
  p.stale_after_s = 0.5;
  OdometryTracker t{p};
  EXPECT_FALSE(t.stale(10'000'000));  // nothing yet: not stale, unreachable is another fault
  t.track(with_wall_clock(sample(10, 1'000'000, 0, 0, 0), 1'700'000'000'000'000));
  EXPECT_FALSE(t.stale(1'400'000));
  EXPECT_TRUE(t.stale(1'600'000));
  // A new seq whose wall-clock time stepped back 1 h: fresh, as the monotonic clock says.
  t.track(with_wall_clock(sample(11, 1'600'000, 0, 0, 0), 1'699'996'400'600'000));
  EXPECT_EQ(t.last_new_mono_us(), 1'600'000);
  EXPECT_FALSE(t.stale(1'700'000));
  EXPECT_TRUE(t.stale(2'200'000));
}

// ---- health and logging ----

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

// ---- motion ----

CommandParams limits() {
  CommandParams p;
  p.rate_hz = 50.0;
  p.deadman_s = 0.2;
  p.max_linear_speed = 0.5;
  p.max_angular_speed = 1.0;
  p.max_linear_accel = 1.0;
  p.max_angular_accel = 2.0;
  return p;
}

TEST(Motion, ClampSpeedKeepsTheDirection) {
  const Velocity v = clamp_speed(Velocity{3.0, 4.0, -5.0}, limits());
  EXPECT_NEAR(std::hypot(v.vx, v.vy), 0.5, 1e-12);
  EXPECT_NEAR(v.vy / v.vx, 4.0 / 3.0, 1e-12);
  EXPECT_EQ(v.omega, -1.0);
  const Velocity slow{0.1, -0.1, 0.2};
  EXPECT_EQ(clamp_speed(slow, limits()), slow);
}

TEST(Motion, LimitAccelMovesAlongTheStraightLine) {
  const Velocity v = limit_accel(Velocity{}, Velocity{0.3, 0.4, 1.0}, 0.1, limits());
  EXPECT_NEAR(std::hypot(v.vx, v.vy), 0.1, 1e-12);
  EXPECT_NEAR(v.vy / v.vx, 4.0 / 3.0, 1e-12);
  EXPECT_NEAR(v.omega, 0.2, 1e-12);
  const Velocity near{0.3, 0.39, 0.9};
  EXPECT_EQ(limit_accel(near, Velocity{0.3, 0.4, 1.0}, 0.1, limits()), (Velocity{0.3, 0.4, 1.0}));
}

TEST(MotionGate, OutputsZeroBeforeAnyCommand) {
  MotionGate g(limits());
  EXPECT_EQ(g.step(0), Velocity{});
  EXPECT_TRUE(g.deadman_active());
}

TEST(MotionGate, RampsToTheClampedTargetAtTheAccelLimit) {
  MotionGate g(limits());
  int64_t t = 0;
  g.step(t);
  double last = 0.0;
  for (int i = 1; i <= 40; ++i) {
    t += 20'000;
    ASSERT_TRUE(g.command(Velocity{2.0, 0.0, 0.0}, t));
    const Velocity v = g.step(t);
    EXPECT_LE(v.vx - last, 1.0 * 0.02 + 1e-12) << "step " << i;
    EXPECT_LE(v.vx, 0.5 + 1e-12);
    last = v.vx;
  }
  EXPECT_NEAR(last, 0.5, 1e-12);
  EXPECT_FALSE(g.deadman_active());
}

// Commands `v` and steps the gate every 20 ms, `n` times from `t` on; returns the time after.
int64_t drive(MotionGate& g, const Velocity& v, int n, int64_t t = 0) {
  for (int i = 0; i < n; ++i, t += 20'000) {
    g.command(v, t);
    g.step(t);
  }
  return t;
}

TEST(MotionGate, AfterTheBaseStoppedByItselfTheOutputRampsUpFromRest) {
  MotionGate g(limits());
  int64_t t = drive(g, Velocity{2.0, 0.0, 0.0}, 40);
  g.command(Velocity{2.0, 0.0, 0.0}, t);
  ASSERT_NEAR(g.step(t).vx, 0.5, 1e-12);
  g.base_stopped();  // none of that reached the base (link down): it stands
  t += 20'000;
  g.command(Velocity{2.0, 0.0, 0.0}, t);
  EXPECT_NEAR(g.step(t).vx, 1.0 * 0.02, 1e-12) << "one step of the accel limit, not 0.5 m/s at once";
}

TEST(MotionGate, DeadmanStopsAtOnceWhenCommandsStop) {
  MotionGate g(limits());
  const int64_t t = drive(g, Velocity{0.3, 0.0, 0.5}, 50);
  const int64_t last_command = t - 20'000;
  Velocity v = g.step(last_command + 200'000);  // exactly deadman_s: still moving
  EXPECT_GT(v.vx, 0.0);
  v = g.step(last_command + 200'001);
  EXPECT_EQ(v, Velocity{});
  EXPECT_TRUE(g.deadman_active());
  EXPECT_EQ(g.deadman_trips(), 1);
  EXPECT_EQ(g.step(last_command + 300'000), Velocity{});
  EXPECT_EQ(g.deadman_trips(), 1);
}

TEST(MotionGate, RejectsNonFiniteCommandsAndKeepsTheDeadmanRunning) {
  MotionGate g(limits());
  g.command(Velocity{0.1, 0.0, 0.0}, 0);
  g.step(0);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  EXPECT_FALSE(g.command(Velocity{nan, 0.0, 0.0}, 100'000));
  EXPECT_FALSE(g.command(Velocity{0.0, std::numeric_limits<double>::infinity(), 0.0}, 100'000));
  const Velocity v = g.step(150'000);
  EXPECT_TRUE(std::isfinite(v.vx));
  EXPECT_EQ(g.step(250'000), Velocity{});  // the rejected commands did not refresh the deadman
}

// ---- circle ----

CommandParams circle_limits() {
  CommandParams p = limits();
  p.max_linear_accel = 0.4;
  p.max_angular_accel = 1.0;
  return p;
}

TEST(CircleTrajectory, CruisesSidewaysWithOmegaEqualToSpeedOverRadius) {
  const CircleTrajectory c(CircleSpec{1.0, 0.2, 0}, circle_limits());
  const Velocity v = c.command(10.0);
  EXPECT_EQ(v.vx, 0.0);
  EXPECT_DOUBLE_EQ(v.vy, 0.2);
  EXPECT_DOUBLE_EQ(v.omega, 0.2);
  EXPECT_FALSE(c.finished(1e6));
  EXPECT_TRUE(std::isinf(c.duration()));
}

TEST(CircleTrajectory, NegativeSpeedTurnsTheOtherWay) {
  const CircleTrajectory c(CircleSpec{0.5, -0.2, 0}, circle_limits());
  const Velocity v = c.command(10.0);
  EXPECT_DOUBLE_EQ(v.vy, -0.2);
  EXPECT_DOUBLE_EQ(v.omega, -0.4);
}

TEST(CircleTrajectory, RampsWithinBothAccelLimitsAndStaysOnTheCircle) {
  // R = 0.2: omega's limit 1.0 rad/s² allows only 0.2 m/s² tangentially (< linear 0.4).
  const CircleTrajectory c(CircleSpec{0.2, 0.2, 1}, circle_limits());
  EXPECT_DOUBLE_EQ(c.accel(), 0.2);
  Velocity prev;
  const double dt = 0.001;
  for (double t = dt; t < c.duration() + 0.1; t += dt) {
    const Velocity v = c.command(t);
    EXPECT_LE(std::abs(v.vy - prev.vy), 0.2 * dt + 1e-9);
    EXPECT_LE(std::abs(v.omega - prev.omega), 1.0 * dt + 1e-9);
    if (v.vy != 0.0) {
      EXPECT_NEAR(v.vy / v.omega, 0.2, 1e-12);
    }
    prev = v;
  }
}

TEST(CircleTrajectory, TravelsExactlyTheLapsAndStops) {
  CommandParams p = circle_limits();
  p.max_angular_speed = 5.0;
  // Cruise for two laps, and a lap so short that the speed never reaches V (triangle profile).
  for (const CircleSpec spec : {CircleSpec{1.0, 0.3, 2}, CircleSpec{0.1, 0.4, 1}}) {
    const CircleTrajectory c(spec, p);
    double distance = 0.0;
    double heading = 0.0;
    double peak = 0.0;
    const double dt = 1e-4;
    for (double t = 0.5 * dt; t < c.duration() + 1.0; t += dt) {
      distance += c.command(t).vy * dt;
      peak = std::max(peak, c.command(t).vy);
      heading += c.command(t).omega * dt;
    }
    EXPECT_NEAR(distance, kTwoPi * spec.radius * spec.laps, 1e-3 * spec.laps) << c.describe();
    EXPECT_NEAR(heading, kTwoPi * spec.laps, 1e-2) << c.describe();
    if (spec.radius == 0.1) {
      EXPECT_LT(peak, 0.9 * spec.speed) << "expected a triangle profile";
    } else {
      EXPECT_DOUBLE_EQ(peak, spec.speed);
    }
    EXPECT_TRUE(c.finished(c.duration()));
    EXPECT_FALSE(c.finished(c.duration() - 0.01));
    EXPECT_EQ(c.command(c.duration() + 0.5), Velocity{});
  }
}

TEST(CircleTrajectory, RejectsSpeedsTheLimitsWouldDistort) {
  const CommandParams p = circle_limits();
  EXPECT_THROW(CircleTrajectory(CircleSpec{0.0, 0.2, 0}, p), std::invalid_argument);
  EXPECT_THROW(CircleTrajectory(CircleSpec{1.0, 0.0, 0}, p), std::invalid_argument);
  EXPECT_THROW(CircleTrajectory(CircleSpec{1.0, 0.2, -1}, p), std::invalid_argument);
  try {
    CircleTrajectory(CircleSpec{1.0, 0.8, 0}, p);
    FAIL() << "speed above max_linear_speed accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("max_linear_speed"), std::string::npos);
  }
  try {
    CircleTrajectory(CircleSpec{0.1, 0.2, 0}, p);  // 2 rad/s > 1 rad/s
    FAIL() << "turn rate above max_angular_speed accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("max_angular_speed"), std::string::npos);
  }
}

// ---- parameters ----

TEST(BasedParams, ShippedConfigLoads) {
  BasedParams p;
  load(ParamNode::from_file(WHISKEYE_SOURCE_DIR "/config/based.yaml"), p);
  EXPECT_EQ(p.url, "http://192.168.0.1:80");
  EXPECT_DOUBLE_EQ(p.odometry.poll_rate_hz, 50.0);
}

TEST(BasedParams, UnknownOrOutOfRangeKeysAreErrorsNamingTheKey) {
  BasedParams p;
  try {
    load(ParamNode::from_string("command:\n  deadman: 0.3\n"), p);
    FAIL();
  } catch (const ParamError& e) {
    EXPECT_NE(std::string(e.what()).find("command.deadman"), std::string::npos) << e.what();
  }
  try {
    load(ParamNode::from_string("command:\n  rate_hz: 2\n"), p);
    FAIL();
  } catch (const ParamError& e) {
    EXPECT_NE(std::string(e.what()).find("command.rate_hz"), std::string::npos) << e.what();
  }
  try {
    load(ParamNode::from_string("url: https://192.168.0.1\n"), p);
    FAIL();
  } catch (const ParamError& e) {
    EXPECT_NE(std::string(e.what()).find("url: "), std::string::npos) << e.what();
  }
  EXPECT_THROW(check_url("192.168.0.1:80", "--url"), ParamError);
  EXPECT_NO_THROW(check_url("http://192.168.0.1:80", "--url"));
  BasedParams fresh;
  load(ParamNode::from_string("odometry:\n  poll_rate_hz: 100\n"), fresh);
  EXPECT_DOUBLE_EQ(fresh.odometry.poll_rate_hz, 100.0);
}

}  // namespace
}  // namespace whiskeye::based
