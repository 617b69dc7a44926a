// Camera renderer: geometry of the projection, lighting, noise and determinism.
#include "sim_test_util.h"

#include "whiskeye/sim/renderer.h"

#include <gtest/gtest.h>

#include <cmath>

namespace whiskeye::sim {
namespace {

using test::world_from_yaml;

// A light wall at x = 3 with a dark landmark from y = y0 to y = y1; flat lighting, optional noise.
World landmark_world(double y0, double y1, const std::string& extra = "  camera: {noise_sigma: 0}\n") {
  return world_from_yaml("  patterns: [{name: light, high: 0.8}, {name: dark, high: 0.1}]\n"
                         "  walls: [{from: [3, 3], to: [3, -3], z: [0, 2], pattern: light}]\n"
                         "  visual_landmarks: [{from: [3, " + std::to_string(y1) + "], to: [3, " + std::to_string(y0) +
                         "], z: [0, 2], pattern: dark}]\n"
                         "  lighting: {ambient: 1.0, attenuation: 0.0}\n" + extra);
}

TEST(Renderer, LandmarkAtAKnownBearingAppearsInTheExpectedColumns) {
  const RobotGeometry robot = default_robot_geometry();
  for (const auto& [y0, y1] : {std::pair{0.5, 1.0}, std::pair{-1.2, -0.4}, std::pair{-0.2, 0.3}}) {
    const World world = landmark_world(y0, y1);
    Renderer r(world, robot);
    FastRng rng(1);
    std::vector<uint8_t> img;
    r.render(Pose2{}, 0.0, rng, img);
    const double cam_x = robot.T_base_head.x + robot.camera.p_camera_in_head.x;
    const double b_lo = std::atan2(y0, 3.0 - cam_x);
    const double b_hi = std::atan2(y1, 3.0 - cam_x);
    const int v = r.height() / 2;
    int mismatches = 0;
    int dark = 0;
    for (int u = 0; u < r.width(); ++u) {
      const double b = r.column_bearing(u);
      const bool expect_dark = b > b_lo && b < b_hi;
      const uint8_t px = img[static_cast<std::size_t>(v * r.width() + u)];
      const bool is_dark = px < 100;
      dark += is_dark;
      if (expect_dark != is_dark) ++mismatches;
      if (expect_dark) {
        EXPECT_EQ(px, 26);  // 0.1 · 255
      } else if (!is_dark) {
        EXPECT_EQ(px, 204);  // 0.8 · 255
      }
    }
    EXPECT_LE(mismatches, 1) << "landmark y in [" << y0 << ", " << y1 << "]";
    // And the columns are where the pinhole model puts the landmark's edges.
    EXPECT_NEAR(dark, r.bearing_column(b_lo) - r.bearing_column(b_hi), 1.0);
  }
}

TEST(Renderer, WallTopAndFloorAreWhereThePinholeModelPutsThem) {
  const RobotGeometry robot = default_robot_geometry();
  const World world = landmark_world(5, 6);  // landmark out of view
  Renderer r(world, robot);
  FastRng rng(1);
  std::vector<uint8_t> img;
  r.render(Pose2{}, 0.0, rng, img);
  const double cam_x = robot.T_base_head.x + robot.camera.p_camera_in_head.x;
  const double cam_z = robot.head_height + robot.camera.p_camera_in_head.z;
  const int u = r.width() / 2;
  // The wall's top edge (z = 2) and bottom edge (z = 0) at distance 3 − cam_x on the optical axis.
  const double d = 3.0 - cam_x;
  const double v_top = r.height() / 2.0 - (2.0 - cam_z) * r.focal_length() / d;
  const double v_bottom = r.height() / 2.0 + cam_z * r.focal_length() / d;
  auto at = [&](int v) { return img[static_cast<std::size_t>(v * r.width() + u)]; };
  EXPECT_EQ(at(static_cast<int>(v_top) - 2), static_cast<uint8_t>(std::lround(0.85 * 255)));  // sky
  EXPECT_EQ(at(static_cast<int>(v_top) + 2), 204);                                             // wall
  EXPECT_EQ(at(static_cast<int>(v_bottom) - 2), 204);
  EXPECT_LT(at(static_cast<int>(v_bottom) + 2), 100);  // floor
}

TEST(Renderer, NoiseHasTheConfiguredSigmaAndDependsOnlyOnTheRngState) {
  const RobotGeometry robot = default_robot_geometry();
  const World world = landmark_world(5, 6, "  camera: {noise_sigma: 3.0}\n");
  Renderer r(world, robot);
  std::vector<uint8_t> a;
  std::vector<uint8_t> b;
  std::vector<uint8_t> c;
  FastRng r1(7);
  FastRng r2(7);
  FastRng r3(8);
  r.render(Pose2{}, 0.0, r1, a);
  r.render(Pose2{}, 0.0, r2, b);
  r.render(Pose2{}, 0.0, r3, c);
  EXPECT_EQ(a, b);
  EXPECT_NE(a, c);
  // Statistics over a uniform wall band (rows around the horizon, all columns).
  double sum = 0.0;
  double sum2 = 0.0;
  int n = 0;
  for (int v = r.height() / 2 - 20; v < r.height() / 2 + 20; ++v) {
    for (int u = 0; u < r.width(); ++u) {
      const double x = a[static_cast<std::size_t>(v * r.width() + u)];
      sum += x;
      sum2 += x * x;
      ++n;
    }
  }
  const double mean = sum / n;
  const double sd = std::sqrt(sum2 / n - mean * mean);
  EXPECT_NEAR(mean, 204.0, 0.1);
  EXPECT_NEAR(sd, 3.0, 0.15);  // rounding to integers adds 1/12 of variance
}

TEST(Renderer, LightingGainScalesPixelValues) {
  const RobotGeometry robot = default_robot_geometry();
  const World world = world_from_yaml("  patterns: [{name: light, high: 0.8}]\n"
                                      "  walls: [{from: [3, 3], to: [3, -3], z: [0, 2], pattern: light}]\n"
                                      "  lighting: {ambient: 1.0, attenuation: 0.0, changes: [{start: 1.0, duration: 1.0, gain: 0.5}]}\n"
                                      "  camera: {noise_sigma: 0}\n");
  Renderer r(world, robot);
  FastRng rng(1);
  std::vector<uint8_t> before;
  std::vector<uint8_t> during;
  r.render(Pose2{}, 0.5, rng, before);
  r.render(Pose2{}, 1.5, rng, during);
  const std::size_t centre = static_cast<std::size_t>((r.height() / 2) * r.width() + r.width() / 2);
  EXPECT_EQ(before[centre], 204);
  EXPECT_EQ(during[centre], 102);
}

TEST(Renderer, YuyvCarriesTheGreyLevelsAsLumaWithNeutralChroma) {
  const std::vector<uint8_t> grey{10, 20, 30, 40};
  std::vector<uint8_t> yuyv;
  grey_to_yuyv(grey, 4, 1, yuyv);
  EXPECT_EQ(yuyv, (std::vector<uint8_t>{10, 128, 20, 128, 30, 128, 40, 128}));
}

}  // namespace
}  // namespace whiskeye::sim
