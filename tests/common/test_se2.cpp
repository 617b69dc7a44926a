#include "whiskeye/common/se2.h"
#include "whiskeye/common/utime.h"

#include <gtest/gtest.h>

#include <random>

namespace whiskeye {
namespace {

void expect_pose_near(const Pose2& a, const Pose2& b, double tol = 1e-12) {
  EXPECT_NEAR(a.x, b.x, tol);
  EXPECT_NEAR(a.y, b.y, tol);
  EXPECT_NEAR(angle_diff(a.theta, b.theta), 0.0, tol);
}

TEST(WrapAngle, MapsIntoHalfOpenInterval) {
  EXPECT_DOUBLE_EQ(wrap_angle(0.0), 0.0);
  EXPECT_DOUBLE_EQ(wrap_angle(kPi), kPi);
  EXPECT_DOUBLE_EQ(wrap_angle(-kPi), kPi);
  EXPECT_NEAR(wrap_angle(3 * kPi), kPi, 1e-12);
  EXPECT_NEAR(wrap_angle(-3.5 * kPi), 0.5 * kPi, 1e-12);
  EXPECT_NEAR(wrap_angle(1e6), std::remainder(1e6, kTwoPi), 1e-9);
  for (double a = -50; a < 50; a += 0.37) {
    const double w = wrap_angle(a);
    EXPECT_GT(w, -kPi);
    EXPECT_LE(w, kPi);
    EXPECT_NEAR(std::sin(w), std::sin(a), 1e-9);
    EXPECT_NEAR(std::cos(w), std::cos(a), 1e-9);
  }
}

TEST(WrapAngle, PositiveRangeAndDiff) {
  EXPECT_NEAR(wrap_angle_positive(-0.5), kTwoPi - 0.5, 1e-12);
  EXPECT_NEAR(angle_diff(0.1, kTwoPi - 0.1), 0.2, 1e-12);
  EXPECT_NEAR(angle_diff(-3.1, 3.1), kTwoPi - 6.2, 1e-12);
}

TEST(Se2, ComposeWithInverseIsIdentity) {
  std::mt19937 rng(1);
  std::uniform_real_distribution<double> u(-5, 5);
  for (int i = 0; i < 100; ++i) {
    const Pose2 p{u(rng), u(rng), wrap_angle(u(rng))};
    expect_pose_near(compose(p, inverse(p)), Pose2{});
    expect_pose_near(compose(inverse(p), p), Pose2{});
  }
}

TEST(Se2, ComposeMovesInTheRotatedFrame) {
  const Pose2 a{1.0, 2.0, kPi / 2};
  const Pose2 b{1.0, 0.0, 0.0};  // one metre forward in a's frame = +y in the world
  expect_pose_near(compose(a, b), Pose2{1.0, 3.0, kPi / 2});
}

TEST(Se2, BetweenRecoversRelativePose) {
  const Pose2 w_a{1.0, -2.0, 0.3};
  const Pose2 a_b{0.5, 0.25, -1.0};
  const Pose2 w_b = compose(w_a, a_b);
  expect_pose_near(between(w_a, w_b), a_b);
}

TEST(Se2, InterpolateTakesShortestArc) {
  const Pose2 p = interpolate({0, 0, kPi - 0.1}, {2, 4, -kPi + 0.1}, 0.5);
  EXPECT_NEAR(p.x, 1.0, 1e-12);
  EXPECT_NEAR(p.y, 2.0, 1e-12);
  EXPECT_NEAR(std::abs(p.theta), kPi, 1e-12);
}

TEST(Se2, BodyVelocityIntegrationFollowsTheArc) {
  // Sideways motion with rotation: a circle of radius v/omega around a centre on the robot's right.
  const double v = 0.5, omega = 0.5;  // radius 1 m
  Pose2 p{1.0, 0.0, 0.0};             // at (1,0), facing outwards (+x): moving left = +y = ccw
  for (int i = 0; i < 100; ++i) p = integrate_body_velocity(p, 0.0, v, omega, kTwoPi / omega / 100);
  expect_pose_near(p, Pose2{1.0, 0.0, 0.0}, 1e-9);
  const Pose2 q = integrate_body_velocity({1.0, 0.0, 0.0}, 0.0, v, omega, kPi / omega);
  expect_pose_near(q, Pose2{-1.0, 0.0, kPi}, 1e-9);
}

TEST(Utime, RoundTripsSeconds) {
  EXPECT_EQ(seconds_to_utime(1.5), 1'500'000);
  EXPECT_EQ(seconds_to_utime(-0.0000014), -1);
  EXPECT_DOUBLE_EQ(utime_to_seconds(2'250'000), 2.25);
  EXPECT_DOUBLE_EQ(utime_delta_seconds(1'000'000, 3'500'000), 2.5);
}

}  // namespace
}  // namespace whiskeye
