// Unit tests of based's pure parts: speed and acceleration limits, the deadman gate (motion.h).
#include "whiskeye/based/motion.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

namespace whiskeye::based {
namespace {

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

}  // namespace
}  // namespace whiskeye::based
