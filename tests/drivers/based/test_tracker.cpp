// Unit tests of based's pure parts: odometry sequence and jump tracking, staleness (tracker.h).
#include "whiskeye/based/tracker.h"
#include "whiskeye/common/se2.h"

#include <gtest/gtest.h>

#include <cmath>

namespace whiskeye::based {
namespace {

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

}  // namespace
}  // namespace whiskeye::based
