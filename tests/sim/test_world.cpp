// World loading and the 2-D ray geometry.
#include "sim_test_util.h"

#include <gtest/gtest.h>

#include <cmath>
#include <tuple>

namespace whiskeye::sim {
namespace {

using test::world_from_yaml;

TEST(World, LoadsTheDefaultAliasedArena) {
  const World w = load_world_file(test::source_path("config/worlds/aliased_arena.yaml"));
  EXPECT_EQ(w.walls.size(), 4u);
  EXPECT_EQ(w.landmarks.size(), 4u);
  EXPECT_EQ(w.solids.size(), 3u);
  EXPECT_DOUBLE_EQ(w.trajectory.radius, 1.0);
  EXPECT_TRUE(w.trajectory.outwards);
  EXPECT_GE(w.trajectory.laps, 3);
}

TEST(World, DefaultArenaIsAliasedForEachSenseAlone) {
  const World w = load_world_file(test::source_path("config/worlds/aliased_arena.yaml"));
  // Vision: two landmarks share a pattern and are point-symmetric about the trajectory centre.
  int same_pattern_pairs = 0;
  for (std::size_t i = 0; i < w.landmarks.size(); ++i) {
    for (std::size_t j = i + 1; j < w.landmarks.size(); ++j) {
      const Panel& a = w.landmarks[i];
      const Panel& b = w.landmarks[j];
      if (a.pattern != b.pattern) continue;
      EXPECT_NEAR(a.from.x, -b.from.x, 1e-9);
      EXPECT_NEAR(a.from.y, -b.from.y, 1e-9);
      ++same_pattern_pairs;
    }
  }
  EXPECT_EQ(same_pattern_pairs, 1);
  // Touch: two solids with the same footprint up to a rigid motion (same perimeter and radius).
  const Solid& box1 = w.solids[0];
  const Solid& box2 = w.solids[1];
  EXPECT_NEAR(box1.perimeter_at.back(), box2.perimeter_at.back(), 1e-9);
  EXPECT_NEAR(box1.radius, box2.radius, 1e-9);
  EXPECT_NEAR(std::hypot(box1.centre.x, box1.centre.y), std::hypot(box2.centre.x, box2.centre.y), 1e-9);
  EXPECT_NE(w.solids[2].shape, box1.shape);
}

TEST(World, CameraFormatIsYuyvUnlessTheWorldSaysGreyOrMjpegWithItsQuality) {
  const World yuyv = test::arena_with("", "");
  EXPECT_EQ(yuyv.camera.format, CameraFormat::Yuyv);
  EXPECT_EQ(yuyv.camera.jpeg_quality, 85);
  EXPECT_EQ(test::arena_with("format: YUYV", "format: GREY").camera.format, CameraFormat::Grey);
  const World mjpeg = test::arena_with("format: YUYV", "format: MJPEG\n    jpeg_quality: 60");
  EXPECT_EQ(mjpeg.camera.format, CameraFormat::Mjpeg);
  EXPECT_EQ(mjpeg.camera.jpeg_quality, 60);
  for (const auto& [from, to, named] : {std::tuple{"format: YUYV", "format: MJPG", "format"},
                                        std::tuple{"format: YUYV", "format: MJPEG\n    jpeg_quality: 0", "jpeg_quality"},
                                        std::tuple{"format: YUYV", "format: MJPEG\n    jpeg_quality: 101", "jpeg_quality"}}) {
    try {
      test::arena_with(from, to);
      ADD_FAILURE() << to << ": expected a ParamError";
    } catch (const ParamError& e) {
      EXPECT_NE(std::string(e.what()).find(named), std::string::npos) << e.what();
    }
  }
}

TEST(World, RejectsAnUnknownKeyNamingIt) {
  try {
    world_from_yaml("  walls:\n    - {from: [0, 0], to: [1, 0], pattern: p, colour: red}\n  patterns:\n    - {name: p}\n");
    FAIL() << "expected a ParamError";
  } catch (const ParamError& e) {
    EXPECT_NE(std::string(e.what()).find("colour"), std::string::npos) << e.what();
  }
}

TEST(World, RejectsAnUndefinedPatternNamingTheKey) {
  try {
    world_from_yaml("  walls:\n    - {from: [0, 0], to: [1, 0], pattern: nope}\n");
    FAIL() << "expected a ParamError";
  } catch (const ParamError& e) {
    EXPECT_NE(std::string(e.what()).find("walls[0].pattern"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("nope"), std::string::npos) << e.what();
  }
}

TEST(World, RejectsADegeneratePolygon) {
  EXPECT_THROW(world_from_yaml("  patterns: [{name: p}]\n  tactile_landmarks:\n"
                               "    - {shape: polygon, pose: [0, 0, 0], points: [[0, 0], [1, 0], [2, 0]], z: [0, 1], pattern: p}\n"),
               ParamError);
}

// The ParamError message of loading `yaml` (a world's body), or "" if it loads.
std::string world_error(const std::string& yaml) {
  try {
    world_from_yaml(yaml);
    return "";
  } catch (const ParamError& e) {
    return e.what();
  }
}

TEST(World, ATactileLandmarkNameGivenTwiceIsRefusedNamingIt) {
  const std::string box = "{name: box_east, shape: circle, pose: [0, 0, 0], radius: 0.1, z: [0, 0.3], pattern: p}";
  const std::string error = world_error("  patterns: [{name: p}]\n  tactile_landmarks:\n    - " + box + "\n    - " + box + "\n");
  EXPECT_NE(error.find("'world.tactile_landmarks[1].name' repeats the tactile landmark name 'box_east'"), std::string::npos)
      << error;
}

TEST(World, AListLongerThanAWorldNeedsIsRefusedNamingItsLength) {
  std::string changes = "  lighting:\n    changes:\n";
  for (int i = 0; i <= 10000; ++i) changes += "      - {start: " + std::to_string(i) + "}\n";
  const std::string error = world_error(changes);
  EXPECT_NE(error.find("'world.lighting.changes' has 10001 items, at most 10000"), std::string::npos) << error;
  std::string slips = "  faults:\n    odometry_slip:\n";
  for (int i = 0; i <= 1000; ++i) slips += "      - {start: " + std::to_string(2 * i) + ", duration: 1, scale: 1.2}\n";
  EXPECT_NE(world_error(slips).find("'world.faults.odometry_slip' has 1001 items, at most 1000"), std::string::npos)
      << world_error(slips);
}

TEST(World, AFileOfMoreValuesThanAnyWorldHoldsIsRefusedBeforeItIsBuilt) {
  std::string changes = "  lighting:\n    changes:\n";
  for (int i = 0; i < 40000; ++i) changes += "      - {start: 1}\n";  // 3 values each
  EXPECT_NE(world_error(changes).find("more than 100000 values in one file"), std::string::npos);
}

TEST(World, RayThroughACircleEntersAndLeavesAtTheRightDistances) {
  const World w = world_from_yaml("  patterns: [{name: p}]\n  tactile_landmarks:\n"
                                  "    - {shape: circle, pose: [2, 0, 0], radius: 0.5, z: [0, 1], pattern: p}\n");
  std::vector<SolidHit> hits;
  ASSERT_EQ(ray_solid({0, 0}, {1, 0}, w.solids[0], hits), 1);
  EXPECT_NEAR(hits[0].t_in, 1.5, 1e-12);
  EXPECT_NEAR(hits[0].t_out, 2.5, 1e-12);
  EXPECT_NEAR(hits[0].cos_in, 1.0, 1e-12);
  hits.clear();
  EXPECT_EQ(ray_solid({0, 0}, {-1, 0}, w.solids[0], hits), 0);  // behind the ray
  hits.clear();
  EXPECT_EQ(ray_solid({0, 0}, {0, 1}, w.solids[0], hits), 0);   // passes beside it
}

TEST(World, RayThroughAConcavePolygonGivesEachPassage) {
  // A U shape opening towards -y: a ray along x at y = 0.5 crosses both arms.
  const World w = world_from_yaml(
      "  patterns: [{name: p}]\n  tactile_landmarks:\n"
      "    - {shape: polygon, pose: [0, 0, 0], z: [0, 1], pattern: p,\n"
      "       points: [[0, 0], [1, 0], [1, 1], [3, 1], [3, 0], [4, 0], [4, 2], [0, 2]]}\n");
  std::vector<SolidHit> hits;
  ASSERT_EQ(ray_solid({-1, 0.5}, {1, 0}, w.solids[0], hits), 2);
  EXPECT_NEAR(hits[0].t_in, 1.0, 1e-12);
  EXPECT_NEAR(hits[0].t_out, 2.0, 1e-12);
  EXPECT_NEAR(hits[1].t_in, 4.0, 1e-12);
  EXPECT_NEAR(hits[1].t_out, 5.0, 1e-12);
}

TEST(World, PatternsHaveTheirDocumentedValues) {
  const World w = world_from_yaml(
      "  patterns:\n"
      "    - {name: s, type: stripes, period: 0.2, duty: 0.5, low: 0.1, high: 0.9}\n"
      "    - {name: c, type: checker, cell: 0.1, low: 0.2, high: 0.8}\n"
      "    - {name: h, type: stripes, orientation: horizontal, period: 0.2, low: 0.0, high: 1.0}\n");
  const Pattern& s = w.patterns[0];
  EXPECT_DOUBLE_EQ(s.value(0.05, 0.3), 0.1);
  EXPECT_DOUBLE_EQ(s.value(0.15, 0.3), 0.9);
  EXPECT_DOUBLE_EQ(s.value(-0.05, 0.3), 0.9);  // periodic below zero too
  const Pattern& c = w.patterns[1];
  EXPECT_DOUBLE_EQ(c.value(0.05, 0.05), 0.2);
  EXPECT_DOUBLE_EQ(c.value(0.15, 0.05), 0.8);
  EXPECT_DOUBLE_EQ(c.value(0.15, 0.15), 0.2);
  EXPECT_DOUBLE_EQ(w.patterns[2].value(0.0, 0.05), 0.0);
  EXPECT_DOUBLE_EQ(w.patterns[2].value(0.0, 0.15), 1.0);
}

TEST(World, TrajectoryRevolvesFacingOutwardsMovingSideways) {
  const World w = world_from_yaml("  trajectory: {radius: 1.0, speed: 0.1, start_angle_deg: 0}\n");
  const Trajectory& t = w.trajectory;
  const Pose2 p0 = t.pose_at(0.0);
  EXPECT_NEAR(p0.x, 1.0, 1e-12);
  EXPECT_NEAR(p0.y, 0.0, 1e-12);
  EXPECT_NEAR(p0.theta, 0.0, 1e-12);
  const Pose2 q = t.pose_at(t.lap_time() / 4.0);
  EXPECT_NEAR(q.x, 0.0, 1e-9);
  EXPECT_NEAR(q.y, 1.0, 1e-9);
  EXPECT_NEAR(q.theta, kPi / 2.0, 1e-9);
  // The body velocity integrates to the same path.
  double vx;
  double vy;
  double om;
  t.body_velocity(vx, vy, om);
  EXPECT_DOUBLE_EQ(vx, 0.0);
  EXPECT_GT(vy, 0.0);
  const Pose2 r = integrate_body_velocity(p0, vx, vy, om, 3.0);
  const Pose2 truth = t.pose_at(3.0);
  EXPECT_NEAR(r.x, truth.x, 1e-9);
  EXPECT_NEAR(r.y, truth.y, 1e-9);
  EXPECT_NEAR(r.theta, truth.theta, 1e-9);
}

TEST(World, LightingAppliesTimedChanges) {
  const World w = world_from_yaml("  lighting: {brightness: 0.8, changes: [{start: 2.0, duration: 0.5, gain: 2.0}]}\n");
  EXPECT_DOUBLE_EQ(w.lighting.gain_at(1.9), 0.8);
  EXPECT_DOUBLE_EQ(w.lighting.gain_at(2.2), 1.6);
  EXPECT_DOUBLE_EQ(w.lighting.gain_at(2.5), 0.8);
}

}  // namespace
}  // namespace whiskeye::sim
