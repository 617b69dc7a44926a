#include "whiskeye/common/robot_geometry.h"

#include <gtest/gtest.h>

#include <cmath>

namespace whiskeye {
namespace {

double norm(const Vec3& v) { return std::sqrt(v.x * v.x + v.y * v.y + v.z * v.z); }

TEST(RobotGeometry, ConfigFileEqualsBuiltInDefaults) {
  RobotGeometry from_file = default_robot_geometry();
  const ParamNode root = ParamNode::from_file(WHISKEYE_SOURCE_DIR "/config/robot.yaml");
  load(root.section("robot"), from_file);
  root.check_no_unknown_keys();
  EXPECT_EQ(from_file, default_robot_geometry());
}

TEST(RobotGeometry, NumbersWhiskersRowMajorWithSides) {
  const RobotGeometry g = default_robot_geometry();
  EXPECT_EQ(g.whiskers[0].row, 0);
  EXPECT_EQ(g.whiskers[0].column, 0);
  EXPECT_EQ(g.whiskers[23].row, 3);
  EXPECT_EQ(g.whiskers[23].column, 5);
  EXPECT_GT(g.whiskers[1].p_base_in_head.y, 0.0);   // left
  EXPECT_LT(g.whiskers[4].p_base_in_head.y, 0.0);   // right
  EXPECT_NEAR(g.whiskers[18].length, 0.1717, 1e-12);  // bottom row: longest
}

TEST(RobotGeometry, ProtractionSweepsBothSidesForward) {
  const RobotGeometry g = default_robot_geometry();
  for (int w = 0; w < kNumWhiskers; ++w) {
    const Vec3 rest = g.whisker_direction(w, 0.0);
    const Vec3 protracted = g.whisker_direction(w, deg_to_rad(40));
    EXPECT_NEAR(norm(rest), 1.0, 1e-12);
    EXPECT_GT(protracted.x, rest.x) << "whisker " << w;                       // more forward
    EXPECT_LT(std::abs(protracted.y), std::abs(rest.y)) << "whisker " << w;  // less lateral
    EXPECT_NEAR(protracted.z, rest.z, 1e-12);  // rotation about the head's z axis
  }
}

TEST(RobotGeometry, WhiskerPointLiesAlongTheWhisker) {
  const RobotGeometry g = default_robot_geometry();
  const Vec3 p = g.whisker_point(5, 0.3, 0.05);
  const Vec3 b = g.whiskers[5].p_base_in_head;
  const Vec3 d{p.x - b.x, p.y - b.y, p.z - b.z};
  EXPECT_NEAR(norm(d), 0.05, 1e-12);
}

TEST(RobotGeometry, RejectsWrongLayoutNamingTheKey) {
  RobotGeometry g = default_robot_geometry();
  const ParamNode n = ParamNode::from_string("whisker_layout: {lengths_by_row: [0.1, 0.2]}", "r.yaml");
  try {
    load(n, g);
    FAIL();
  } catch (const ParamError& e) {
    EXPECT_NE(std::string(e.what()).find("'whisker_layout.lengths_by_row' must have 4 values"), std::string::npos);
  }
}

}  // namespace
}  // namespace whiskeye
