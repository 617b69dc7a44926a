// Unit tests of based's pure parts: the circle trajectory within the motion limits (circle.h).
#include "whiskeye/based/circle.h"
#include "whiskeye/based/motion.h"
#include "whiskeye/common/se2.h"

#include <gtest/gtest.h>

#include <cmath>

namespace whiskeye::based {
namespace {

// test_motion.cpp's limits with gentler accelerations.
CommandParams circle_limits() {
  CommandParams p;
  p.rate_hz = 50.0;
  p.deadman_s = 0.2;
  p.max_linear_speed = 0.5;
  p.max_angular_speed = 1.0;
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

}  // namespace
}  // namespace whiskeye::based
