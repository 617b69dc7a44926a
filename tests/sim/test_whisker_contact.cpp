// Swept whisker/world intersection against closed-form expectations.
#include "sim_test_util.h"

#include "whiskeye/sim/whisker_contact.h"

#include <gtest/gtest.h>

#include <cmath>

namespace whiskeye::sim {
namespace {

using test::world_from_yaml;

// A wall along head y at head x = distance, higher than the robot.
World wall_at(double distance) {
  return world_from_yaml("  patterns: [{name: p}]\n  walls:\n    - {from: [" + std::to_string(distance) +
                         ", -1], to: [" + std::to_string(distance) + ", 1], z: [0, 2], pattern: p}\n");
}

TEST(WhiskerContact, WhiskerSweptAgainstAWallTouchesItWithItsTipAtTheExpectedAngle) {
  const RobotGeometry robot = default_robot_geometry();
  for (const double distance : {0.12, 0.15, 0.18}) {
    const World world = wall_at(distance);
    for (const int w : {18, 21, 12, 0}) {  // row 3 left/right front, row 2 left front, row 0 left front
      const WhiskerGeometry& g = robot.whiskers[static_cast<std::size_t>(w)];
      const double reach = g.length * std::cos(g.elevation);
      const double c = (distance - g.p_base_in_head.x) / reach;
      const auto contact = find_whisker_contact(world, robot, Pose2{}, w);
      if (c >= 1.0 || std::acos(c) < std::abs(g.azimuth0) - SweepParams{}.theta_hi) {
        EXPECT_FALSE(contact) << "whisker " << w << " cannot reach a wall at " << distance;
        continue;
      }
      // The tip reaches the wall when base_x + reach cos(azimuth) = distance; azimuth = azimuth0 − side θ.
      const double expected_theta = g.side * (g.azimuth0 - g.side * std::acos(c));
      ASSERT_TRUE(contact) << "whisker " << w << " at " << distance;
      EXPECT_NEAR(contact->theta, expected_theta, 1e-4) << "whisker " << w << " at " << distance;
      EXPECT_NEAR(contact->radial, g.length, 1e-3);
      EXPECT_NEAR(contact->p_contact_in_head.x, distance, 1e-4);
      EXPECT_EQ(contact->solid, -1);
    }
  }
}

TEST(WhiskerContact, LeftAndRightWhiskersTouchASymmetricWallAtTheSameAngle) {
  const RobotGeometry robot = default_robot_geometry();
  const World world = wall_at(0.15);
  for (int row = 0; row < kWhiskerRows; ++row) {
    for (int col = 0; col < 3; ++col) {
      const auto left = find_whisker_contact(world, robot, Pose2{}, row * 6 + col);
      const auto right = find_whisker_contact(world, robot, Pose2{}, row * 6 + col + 3);
      ASSERT_EQ(left.has_value(), right.has_value());
      if (left) {
        EXPECT_NEAR(left->theta, right->theta, 1e-6);
        EXPECT_NEAR(left->p_contact_in_head.y, -right->p_contact_in_head.y, 1e-6);
      }
    }
  }
}

TEST(WhiskerContact, ThinPostIsTouchedAlongTheShaftAtTheTangentAngle) {
  const RobotGeometry robot = default_robot_geometry();
  const int w = 18;  // row 3, left front
  const WhiskerGeometry& g = robot.whiskers[w];
  // A post of radius R at 0.09 m from the base, bearing 40° from head x (inside the sweep).
  const double rho = 0.09;
  const double R = 0.005;
  const double bearing = deg_to_rad(40.0);
  const double px = g.p_base_in_head.x + rho * std::cos(bearing);
  const double py = g.p_base_in_head.y + rho * std::sin(bearing);
  const World world = world_from_yaml("  patterns: [{name: p}]\n  tactile_landmarks:\n    - {shape: circle, pose: [" +
                                      std::to_string(px) + ", " + std::to_string(py) + ", 0], radius: " +
                                      std::to_string(R) + ", z: [0, 1], pattern: p, stiffness: 0.5}\n");
  const auto contact = find_whisker_contact(world, robot, Pose2{}, w);
  ASSERT_TRUE(contact);
  // Protraction lowers a left whisker's azimuth: it meets the post's far tangent first.
  const double azimuth = bearing + std::asin(R / rho);
  EXPECT_NEAR(contact->theta, g.azimuth0 - azimuth, 1e-4);
  EXPECT_NEAR(contact->radial, std::sqrt(rho * rho - R * R) / std::cos(g.elevation), 1e-4);
  EXPECT_EQ(contact->solid, 0);
  EXPECT_DOUBLE_EQ(contact->stiffness, 0.5);
}

TEST(WhiskerContact, ObjectBelowTheWhiskerIsNotTouched) {
  const RobotGeometry robot = default_robot_geometry();
  const World low = world_from_yaml("  patterns: [{name: p}]\n  tactile_landmarks:\n"
                                    "    - {shape: circle, pose: [0.12, 0.08, 0], radius: 0.03, z: [0, 0.1], pattern: p}\n");
  const World tall = world_from_yaml("  patterns: [{name: p}]\n  tactile_landmarks:\n"
                                     "    - {shape: circle, pose: [0.12, 0.08, 0], radius: 0.03, z: [0, 0.5], pattern: p}\n");
  for (int w = 0; w < kNumWhiskers; ++w) EXPECT_FALSE(find_whisker_contact(low, robot, Pose2{}, w)) << w;
  int touched = 0;
  for (int w = 0; w < kNumWhiskers; ++w) touched += find_whisker_contact(tall, robot, Pose2{}, w).has_value();
  EXPECT_GT(touched, 0);
}

TEST(WhiskerContact, ContactFollowsTheHeadPose) {
  // The same wall seen from a moved and turned head gives the same contact in the head frame.
  const RobotGeometry robot = default_robot_geometry();
  const Pose2 T_world_head{1.0, 2.0, 0.7};
  double ax;
  double ay;
  double bx;
  double by;
  transform_point(T_world_head, 0.15, -1.0, ax, ay);
  transform_point(T_world_head, 0.15, 1.0, bx, by);
  const World world = world_from_yaml("  patterns: [{name: p}]\n  walls:\n    - {from: [" + std::to_string(ax) + ", " +
                                      std::to_string(ay) + "], to: [" + std::to_string(bx) + ", " + std::to_string(by) +
                                      "], z: [0, 2], pattern: p}\n");
  const auto moved = find_whisker_contact(world, robot, T_world_head, 18);
  const auto here = find_whisker_contact(wall_at(0.15), robot, Pose2{}, 18);
  ASSERT_TRUE(moved);
  ASSERT_TRUE(here);
  EXPECT_NEAR(moved->theta, here->theta, 1e-4);
}

}  // namespace
}  // namespace whiskeye::sim
