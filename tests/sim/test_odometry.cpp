// Simulated odometry: exact without noise, drifting as configured with bias, seeded noise.
#include "sim_test_util.h"

#include "whiskeye/sim/odometry.h"

#include <gtest/gtest.h>

namespace whiskeye::sim {
namespace {

OdometrySample run(const OdometryNoise& noise, const Trajectory& t, double seconds, uint64_t seed) {
  OdometryModel odo(noise, t.pose_at(0.0), seed);
  double vx;
  double vy;
  double om;
  t.body_velocity(vx, vy, om);
  OdometrySample s = odo.step(vx, vy, om, 0.0);
  for (int k = 1; k <= static_cast<int>(seconds * 50); ++k) s = odo.step(vx, vy, om, 0.02);
  return s;
}

TEST(Odometry, WithoutNoiseItFollowsTheTrueMotion) {
  const World w = test::world_from_yaml("  trajectory: {radius: 1.0, speed: 0.1, start_angle_deg: 30}\n");
  const OdometryNoise none{0.0, 0.0, 0.0, 0.0, 0.0, 1.0, true};
  const OdometrySample s = run(none, w.trajectory, 20.0, 1);
  const Pose2 truth = w.trajectory.pose_at(20.0);
  EXPECT_NEAR(s.pose.x, truth.x, 1e-9);
  EXPECT_NEAR(s.pose.y, truth.y, 1e-9);
  EXPECT_NEAR(s.pose.theta, truth.theta, 1e-9);
  EXPECT_NEAR(s.vy, 0.1, 1e-12);
}

TEST(Odometry, HeadingBiasDriftsAtTheConfiguredRate) {
  const World w = test::world_from_yaml("  trajectory: {radius: 1.0, speed: 0.1}\n");
  OdometryNoise biased{0.0, 0.0, 0.0, 0.0, 0.01, 1.0, true};
  const OdometrySample s = run(biased, w.trajectory, 10.0, 1);
  EXPECT_NEAR(angle_diff(s.pose.theta, w.trajectory.pose_at(10.0).theta), 0.1, 1e-9);
  EXPECT_NEAR(s.omega, 0.11, 1e-12);
}

TEST(Odometry, NoiseIsSeeded) {
  const World w = test::world_from_yaml("  trajectory: {radius: 1.0, speed: 0.1}\n");
  const OdometryNoise noisy{};
  const OdometrySample a = run(noisy, w.trajectory, 5.0, 3);
  const OdometrySample b = run(noisy, w.trajectory, 5.0, 3);
  const OdometrySample c = run(noisy, w.trajectory, 5.0, 4);
  EXPECT_EQ(a.pose, b.pose);
  EXPECT_NE(a.pose, c.pose);
  // Starting at the origin unless told otherwise: the first sample is the odometry frame's origin.
  OdometryModel odo(noisy, Pose2{}, 1);
  EXPECT_EQ(odo.step(0.0, 0.1, 0.1, 0.0).pose, Pose2{});
}

}  // namespace
}  // namespace whiskeye::sim
