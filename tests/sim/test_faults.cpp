// Injected sensor faults (World::faults): the world file's `faults:` section, what each fault does to
// the simulated sensors (as whiskerd, camerad and based would show it), its SIM_FAULT record, and
// the boards' CAN traffic under it.
#include "sim_test_util.h"

#include "whiskeye/sim/can_log.h"
#include "whiskeye/sim/lcm_sink.h"
#include "whiskeye/sim/simulator.h"

#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <set>

namespace whiskeye::sim {
namespace {

using test::world_from_yaml;

constexpr int64_t kStart = SimParams{}.start_utime;

double seconds(int64_t utime) { return static_cast<double>(utime - kStart) * 1e-6; }

struct Frame {
  int64_t utime;
  int64_t seq;
  std::vector<uint8_t> grey;
};

struct Odometry {
  int64_t utime;
  OdometrySample odom;
};

struct Recorder : SimSink {
  std::vector<rcp::WhiskerSample> samples;
  std::vector<WhiskerHealth> health;
  std::vector<rcp::WhiskCycle> cycles;
  std::vector<Frame> frames;
  std::vector<Odometry> odom;
  std::vector<FaultEvent> faults;
  std::vector<std::pair<int64_t, Pose2>> truth;
  std::vector<ContactTruth::Point> contacts;  // true contact onsets
  std::vector<int64_t> times;  // every output, in the order delivered
  void whisker_sample(const rcp::WhiskerSample& s, const WhiskerHealth& h) override {
    samples.push_back(s);
    health.push_back(h);
    times.push_back(s.utime);
  }
  void rcp_state(const rcp::ControlOutput& o) override { times.push_back(o.utime); }
  void whisk_cycle(const rcp::WhiskCycle& c) override {
    cycles.push_back(c);
    times.push_back(c.utime_end);
  }
  void contact_truth(const ContactTruth& t) override {
    contacts.insert(contacts.end(), t.points.begin(), t.points.end());
    times.push_back(t.utime);
  }
  void odometry(int64_t u, int64_t, const OdometrySample& o) override {
    odom.push_back({u, o});
    times.push_back(u);
  }
  void ground_truth(int64_t u, const Pose2& p) override {
    truth.emplace_back(u, p);
    times.push_back(u);
  }
  void camera(int64_t u, int64_t seq, const std::vector<uint8_t>& g, int, int) override {
    frames.push_back({u, seq, g});
    times.push_back(u);
  }
  void fault(const FaultEvent& e) override {
    faults.push_back(e);
    times.push_back(e.utime);
  }
};

// The default arena started where the robot passes box_north (84°): real deflections.
World arena() {
  World w = load_world_file(test::source_path("config/worlds/aliased_arena.yaml"));
  w.trajectory.start_angle = deg_to_rad(84.0);
  return w;
}

Recorder run(const World& world, double duration, std::vector<FaultRecord>* records = nullptr) {
  SimParams p;
  p.duration = duration;
  p.seed = 4;
  Simulator sim(world, default_robot_geometry(), rcp::ControllerParams{}, rcp::PlantParams{}, p);
  Recorder rec;
  while (sim.step(rec)) {
  }
  if (records) *records = sim.faults();
  return rec;
}

bool in(int64_t utime, double start, double duration) {
  const double t = seconds(utime);
  return t >= start - 1e-9 && t < start + duration - 1e-9;
}

// ---- the world file ----

TEST(WorldFaults, LoadsTheFaultsSectionInTheWorldGeneratorsFormat) {
  const World w = world_from_yaml(
      "  faults:\n"
      "    dead_whiskers: [3, 10, 17, 22]\n"
      "    board_offline: [{board: 2, start: 40.0, duration: 30.0}]\n"
      "    camera_blackout: [{start: 100.0, duration: 10.0}]\n"
      "    camera_freeze: [{start: 150.0, duration: 5.0}]\n"
      "    odometry_slip: [{start: 200.0, duration: 10.0, scale: 1.2}]\n");
  const Faults& f = w.faults;
  EXPECT_EQ(f.dead_whiskers, (std::vector<int>{3, 10, 17, 22}));
  ASSERT_EQ(f.board_offline.size(), 1u);
  EXPECT_EQ(f.board_offline[0].board, 2);
  EXPECT_DOUBLE_EQ(f.board_offline[0].start, 40.0);
  EXPECT_DOUBLE_EQ(f.board_offline[0].duration, 30.0);
  ASSERT_EQ(f.camera_blackout.size(), 1u);
  EXPECT_DOUBLE_EQ(f.camera_blackout[0].start, 100.0);
  EXPECT_DOUBLE_EQ(f.camera_blackout[0].duration, 10.0);
  ASSERT_EQ(f.camera_freeze.size(), 1u);
  EXPECT_DOUBLE_EQ(f.camera_freeze[0].start, 150.0);
  EXPECT_DOUBLE_EQ(f.camera_freeze[0].duration, 5.0);
  ASSERT_EQ(f.odometry_slip.size(), 1u);
  EXPECT_DOUBLE_EQ(f.odometry_slip[0].start, 200.0);
  EXPECT_DOUBLE_EQ(f.odometry_slip[0].duration, 10.0);
  EXPECT_DOUBLE_EQ(f.odometry_slip[0].scale, 1.2);
}

TEST(WorldFaults, AWorldWithoutFaultsOrWithEmptyListsHasNone) {
  for (const char* yaml : {"  name: x\n", "  faults: {}\n",
                           "  faults: {dead_whiskers: [], board_offline: [], camera_blackout: [], camera_freeze: [],"
                           " odometry_slip: []}\n"}) {
    const Faults f = world_from_yaml(yaml).faults;
    EXPECT_TRUE(f.dead_whiskers.empty() && f.board_offline.empty() && f.camera_blackout.empty() &&
                f.camera_freeze.empty() && f.odometry_slip.empty())
        << yaml;
  }
}

std::string error_of(const std::string& faults_yaml) {
  try {
    world_from_yaml("  faults:\n" + faults_yaml);
  } catch (const ParamError& e) {
    return e.what();
  }
  return "";
}

TEST(WorldFaults, RejectsOutOfRangeValuesNamingTheKey) {
  const std::pair<const char*, const char*> cases[] = {
      {"    dead_whiskers: [3, 24]\n", "world.faults.dead_whiskers"},
      {"    dead_whiskers: [-1]\n", "world.faults.dead_whiskers"},
      {"    dead_whiskers: [5, 5]\n", "world.faults.dead_whiskers"},
      {"    board_offline: [{board: 6, start: 1, duration: 1}]\n", "world.faults.board_offline[0].board"},
      {"    board_offline: [{board: -1, start: 1, duration: 1}]\n", "world.faults.board_offline[0].board"},
      {"    camera_blackout: [{start: -0.5, duration: 1}]\n", "world.faults.camera_blackout[0].start"},
      {"    camera_blackout: [{start: 2e6, duration: 1}]\n", "world.faults.camera_blackout[0].start"},
      {"    camera_freeze: [{start: 1, duration: 0}]\n", "world.faults.camera_freeze[0].duration"},
      {"    camera_freeze: [{start: 1, duration: 2e6}]\n", "world.faults.camera_freeze[0].duration"},
      {"    odometry_slip: [{start: 1, duration: 1, scale: 0.05}]\n", "world.faults.odometry_slip[0].scale"},
      {"    odometry_slip: [{start: 1, duration: 1, scale: 11}]\n", "world.faults.odometry_slip[0].scale"},
      {"    odometry_slip: [{start: 1, duration: 1}]\n", "world.faults.odometry_slip[0].scale"},
      {"    board_offline: [{start: 1, duration: 1}]\n", "world.faults.board_offline[0].board"},
      {"    camera_blackout: [{duration: 1}]\n", "world.faults.camera_blackout[0].start"},
      {"    camera_blackout: [{start: 1}]\n", "world.faults.camera_blackout[0].duration"},
      {"    dead_whiskers: 3\n", "world.faults.dead_whiskers"},
  };
  for (const auto& [yaml, key] : cases) EXPECT_NE(error_of(yaml).find(key), std::string::npos) << yaml << " -> " << error_of(yaml);
}

TEST(WorldFaults, RejectsAnUnknownKeyNamingIt) {
  EXPECT_NE(error_of("    dead_whisker: [3]\n").find("world.faults.dead_whisker"), std::string::npos);
  EXPECT_NE(error_of("    board_offline: [{board: 1, start: 1, duration: 1, stale: true}]\n")
                .find("world.faults.board_offline[0].stale"),
            std::string::npos);
  EXPECT_NE(error_of("    camera_freeze: [{start: 1, duration: 1, scale: 2}]\n").find("world.faults.camera_freeze[0].scale"),
            std::string::npos);
}

TEST(WorldFaults, RejectsOverlappingIntervalsOfOneSensorButNotOfDifferentBoards) {
  EXPECT_NE(error_of("    camera_blackout: [{start: 1, duration: 2}, {start: 2.5, duration: 1}]\n")
                .find("world.faults.camera_blackout[1].start"),
            std::string::npos);
  EXPECT_NE(error_of("    board_offline: [{board: 1, start: 1, duration: 2}, {board: 1, start: 0, duration: 1.5}]\n")
                .find("world.faults.board_offline[1].start"),
            std::string::npos);
  EXPECT_EQ(error_of("    board_offline: [{board: 1, start: 1, duration: 2}, {board: 2, start: 1, duration: 2}]\n"), "");
  EXPECT_EQ(error_of("    odometry_slip: [{start: 1, duration: 1, scale: 2}, {start: 2, duration: 1, scale: 0.5}]\n"), "")
      << "back to back is no overlap";
}

TEST(WorldFaults, RefusesNonFiniteNumbersAnywhereNamingTheKey) {
  const std::pair<const char*, const char*> cases[] = {
      {"  trajectory: {centre: [.nan, 0]}\n", "world.trajectory.centre"},
      {"  trajectory: {radius: .inf}\n", "world.trajectory.radius"},
      {"  patterns: [{name: p}]\n  walls: [{from: [0, -.inf], to: [1, 0], pattern: p}]\n", "world.walls[0].from"},
      {"  patterns: [{name: p}]\n  tactile_landmarks:\n"
       "    - {shape: polygon, pose: [0, 0, 0], points: [[0, 0], [1, 0], [1, .nan]], z: [0, 1], pattern: p}\n",
       "world.tactile_landmarks[0].points"},
      {"  patterns: [{name: p}]\n  tactile_landmarks: [{shape: circle, pose: [.nan, 0, 0], radius: 0.1, pattern: p}]\n",
       "world.tactile_landmarks[0].pose"},
      {"  lighting: {changes: [{start: .inf, duration: 1, gain: 2}]}\n", "world.lighting.changes[0].start"},
      {"  faults: {camera_freeze: [{start: .nan, duration: 1}]}\n", "world.faults.camera_freeze[0].start"},
  };
  for (const auto& [yaml, key] : cases) {
    try {
      world_from_yaml(yaml);
      ADD_FAILURE() << "accepted " << yaml;
    } catch (const ParamError& e) {
      EXPECT_NE(std::string(e.what()).find(key), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find("not a finite number"), std::string::npos) << e.what();
    }
  }
}

TEST(WorldFaults, LoadsKidnapsInTimeOrder) {
  const World w = world_from_yaml("  faults:\n    kidnap: [{at: 70.5, to_angle: 1.5}, {at: 140, to_angle: -3.0}]\n");
  ASSERT_EQ(w.faults.kidnap.size(), 2u);
  EXPECT_DOUBLE_EQ(w.faults.kidnap[0].at, 70.5);
  EXPECT_DOUBLE_EQ(w.faults.kidnap[0].to_angle, 1.5);
  EXPECT_DOUBLE_EQ(w.faults.kidnap[1].at, 140.0);
  EXPECT_DOUBLE_EQ(w.faults.kidnap[1].to_angle, -3.0);
  EXPECT_TRUE(world_from_yaml("  faults: {}\n").faults.kidnap.empty());
}

TEST(WorldFaults, RejectsBadKidnapsNamingTheKey) {
  const std::pair<const char*, const char*> cases[] = {
      {"    kidnap: [{to_angle: 1}]\n", "world.faults.kidnap[0].at"},
      {"    kidnap: [{at: 10}]\n", "world.faults.kidnap[0].to_angle"},
      {"    kidnap: [{at: 0, to_angle: 1}]\n", "world.faults.kidnap[0].at"},
      {"    kidnap: [{at: -5, to_angle: 1}]\n", "world.faults.kidnap[0].at"},
      {"    kidnap: [{at: 2e6, to_angle: 1}]\n", "world.faults.kidnap[0].at"},
      {"    kidnap: [{at: 10, to_angle: 6.3}]\n", "world.faults.kidnap[0].to_angle"},
      {"    kidnap: [{at: 10, to_angle: -7}]\n", "world.faults.kidnap[0].to_angle"},
      {"    kidnap: [{at: .nan, to_angle: 1}]\n", "world.faults.kidnap[0].at"},
      {"    kidnap: [{at: 10, to_angle: .inf}]\n", "world.faults.kidnap[0].to_angle"},
      {"    kidnap: [{at: 20, to_angle: 1}, {at: 10, to_angle: 2}]\n", "world.faults.kidnap[1].at"},
      {"    kidnap: [{at: 20, to_angle: 1}, {at: 20.0000001, to_angle: 2}]\n", "world.faults.kidnap[1].at"},
      {"    kidnap: [{at: 20, to_angle: 1, to: [0, 0]}]\n", "world.faults.kidnap[0].to"},
      {"    kidnap: {at: 20, to_angle: 1}\n", "world.faults.kidnap"},
  };
  for (const auto& [yaml, key] : cases) {
    const std::string e = error_of(yaml);
    EXPECT_NE(e.find(key), std::string::npos) << yaml << " -> " << e;
    EXPECT_EQ(e.find('\n'), std::string::npos) << "one line: " << e;
  }
  EXPECT_NE(error_of("    kidnap: [{at: 20, to_angle: 1}, {at: 10, to_angle: 2}]\n").find("time order"), std::string::npos);
}

TEST(WorldKidnap, TheBasePoseFollowsThePathFromWhereTheRobotWasPutDown) {
  World w = world_from_yaml("  trajectory: {radius: 1.0, speed: 0.1, start_angle_deg: 0, direction: cw}\n"
                            "  faults: {kidnap: [{at: 10, to_angle: 3.0}, {at: 20, to_angle: -1.0}]}\n");
  const auto on_circle = [](double angle) { return Pose2{std::cos(angle), std::sin(angle), wrap_angle(angle)}; };
  const auto expect_pose = [](const Pose2& a, const Pose2& b, const char* what) {
    EXPECT_NEAR(a.x, b.x, 1e-12) << what;
    EXPECT_NEAR(a.y, b.y, 1e-12) << what;
    EXPECT_NEAR(angle_diff(a.theta, b.theta), 0.0, 1e-12) << what;
  };
  expect_pose(w.base_pose_at(9.998), w.trajectory.pose_at(9.998), "before the first kidnap: the trajectory");
  expect_pose(w.base_pose_at(10.0), on_circle(3.0), "at it: the angle put down at");
  expect_pose(w.base_pose_at(15.0), on_circle(3.0 - 0.5), "then on along the path, clockwise");
  expect_pose(w.base_pose_at(20.0), on_circle(-1.0), "the second kidnap");
  expect_pose(w.base_pose_at(25.0), on_circle(-1.5), "after it");
  w.trajectory.outwards = false;
  EXPECT_NEAR(angle_diff(w.base_pose_at(15.0).theta, 2.5 + kPi), 0.0, 1e-12) << "facing inwards as it would there";
}

// ---- what the faults do ----

TEST(SimulatorFaults, ADeadWhiskerReadsNoDeflectionIsFlaggedFaultyAndIsNaNInEveryWhiskCycle) {
  World w = arena();
  w.faults.dead_whiskers = {3, 22};
  const Recorder rec = run(w, 3.0);
  ASSERT_EQ(rec.samples.size(), 1500u);
  double live_deflection = 0.0;
  for (std::size_t i = 0; i < rec.samples.size(); ++i) {
    const rcp::WhiskerSample& s = rec.samples[i];
    const WhiskerHealth& h = rec.health[i];
    for (int w = 0; w < rcp::kNumWhiskers; ++w) {
      const bool dead = w == 3 || w == 22;
      ASSERT_EQ(h.fault[w], dead) << w;
      ASSERT_FALSE(h.stale[w]);
      ASSERT_EQ(s.valid[w], !dead) << w;
      if (dead) {
        ASSERT_EQ(s.deflection_x[w], 0.0);
        ASSERT_EQ(s.deflection_y[w], 0.0);
      } else {
        live_deflection = std::max(live_deflection, std::hypot(s.deflection_x[w], s.deflection_y[w]));
      }
    }
    // Published as whiskerd publishes a failed sensor.
    const whisker_sample_t m = to_lcm(s, h, rcp::PlantParams{}.saturation);
    ASSERT_TRUE(m.status[3] & whisker_sample_t::STATUS_FAULT);
    ASSERT_TRUE(m.status[22] & whisker_sample_t::STATUS_FAULT);
    ASSERT_FALSE(m.status[3] & whisker_sample_t::STATUS_STALE);
    ASSERT_FALSE(m.status[4] & whisker_sample_t::STATUS_FAULT);
  }
  EXPECT_GT(live_deflection, 0.04) << "the run passes the box: the live whiskers touch it";
  ASSERT_GE(rec.cycles.size(), 2u);
  for (const rcp::WhiskCycle& c : rec.cycles) {
    for (const auto& s : c.samples) {
      ASSERT_TRUE(std::isnan(s.theta[3]) && std::isnan(s.deflection_x[3]) && std::isnan(s.deflection_y[3]));
      ASSERT_TRUE(std::isnan(s.theta[22]));
      ASSERT_FALSE(std::isnan(s.theta[4]) || std::isnan(s.deflection_x[21]));
    }
  }
}

TEST(SimulatorFaults, AnOfflineBoardRepeatsItsLastValuesAsStaleAndIsNaNInTheCycleOnlyWhileOffline) {
  World w = arena();
  w.faults.board_offline = {{{1.0, 1.0}, 1}};  // whiskers 4..7 in [1, 2) s
  const Recorder rec = run(w, 3.5);
  int stale_samples = 0;
  const rcp::WhiskerSample* before = nullptr;
  bool values_change_outside = false;
  for (std::size_t i = 0; i < rec.samples.size(); ++i) {
    const rcp::WhiskerSample& s = rec.samples[i];
    const WhiskerHealth& h = rec.health[i];
    const bool offline = in(s.utime, 1.0, 1.0);
    if (!offline && in(s.utime + 2000, 1.0, 1.0)) before = &s;  // the last sample before it
    for (int w = 0; w < rcp::kNumWhiskers; ++w) {
      const bool affected = offline && w >= 4 && w < 8;
      ASSERT_EQ(h.stale[w], affected) << w << " at " << seconds(s.utime);
      ASSERT_FALSE(h.fault[w]);
      ASSERT_EQ(s.valid[w], !affected) << w << " at " << seconds(s.utime);
      if (affected) {
        ASSERT_NE(before, nullptr);
        ASSERT_EQ(s.theta[w], before->theta[w]);
        ASSERT_EQ(s.deflection_x[w], before->deflection_x[w]);
        ASSERT_EQ(s.deflection_y[w], before->deflection_y[w]);
      }
    }
    if (offline) {
      ++stale_samples;
      const whisker_sample_t m = to_lcm(s, h, rcp::PlantParams{}.saturation);
      ASSERT_EQ(m.status[5] & (whisker_sample_t::STATUS_STALE | whisker_sample_t::STATUS_FAULT),
                whisker_sample_t::STATUS_STALE);
      ASSERT_EQ(m.status[8] & whisker_sample_t::STATUS_STALE, 0);
    } else if (i > 0 && s.theta[5] != rec.samples[i - 1].theta[5]) {
      values_change_outside = true;
    }
  }
  EXPECT_EQ(stale_samples, 500);
  EXPECT_TRUE(values_change_outside);
  int nan_samples = 0;
  for (const rcp::WhiskCycle& c : rec.cycles) {
    for (const auto& s : c.samples) {
      const bool offline = in(s.utime, 1.0, 1.0);
      for (int w = 4; w < 8; ++w) ASSERT_EQ(std::isnan(s.theta[w]), offline) << w << " at " << seconds(s.utime);
      ASSERT_FALSE(std::isnan(s.theta[3]) || std::isnan(s.theta[8]));
      nan_samples += offline;
    }
  }
  EXPECT_GT(nan_samples, 0) << "a completed cycle covers part of the interval";
}

TEST(SimulatorFaults, ACameraBlackoutPublishesNoFramesInItsIntervalAndLaterFramesAreThoseOfTheRunWithoutIt) {
  World w = arena();
  const Recorder clean = run(w, 3.0);
  w.faults.camera_blackout = {{1.0, 1.0}};
  std::vector<FaultRecord> records;
  const Recorder rec = run(w, 3.0, &records);
  ASSERT_EQ(clean.frames.size(), 15u);
  ASSERT_EQ(rec.frames.size(), 10u) << "5 fps: the frames due at 1.0, 1.2, ... 1.8 s are withheld";
  for (std::size_t i = 0; i < rec.frames.size(); ++i) {
    EXPECT_FALSE(in(rec.frames[i].utime, 1.0, 1.0)) << seconds(rec.frames[i].utime);
    EXPECT_EQ(rec.frames[i].seq, static_cast<int64_t>(i)) << "seq counts the frames published";
  }
  EXPECT_EQ(rec.frames[5].utime, kStart + 2'000'000);
  EXPECT_TRUE(rec.frames[5].grey == clean.frames[10].grey);
  ASSERT_EQ(records.size(), 1u);
  EXPECT_EQ(records[0].affected, 5);
}

TEST(SimulatorFaults, ACameraFreezeRepeatsTheLastFrameBeforeItAtTheNormalRateWithNewTimesAndSeq) {
  World w = arena();
  w.faults.camera_freeze = {{1.0, 1.0}};
  const Recorder rec = run(w, 3.0);
  ASSERT_EQ(rec.frames.size(), 15u);
  const Frame& last_before = rec.frames[4];
  ASSERT_EQ(last_before.utime, kStart + 800'000);
  for (std::size_t i = 0; i < rec.frames.size(); ++i) {
    const Frame& f = rec.frames[i];
    EXPECT_EQ(f.seq, static_cast<int64_t>(i));
    EXPECT_EQ(f.utime, kStart + static_cast<int64_t>(i) * 200'000);
    const bool frozen = in(f.utime, 1.0, 1.0);
    EXPECT_EQ(f.grey == last_before.grey, frozen || i == 4) << seconds(f.utime);
  }
}

TEST(SimulatorFaults, OdometrySlipScalesTheMeasuredLinearVelocityDuringItsIntervalOnly) {
  World w = arena();
  w.odometry = {};
  w.odometry.sigma_v = w.odometry.sigma_omega = 0.0;
  w.odometry.bias_vx = w.odometry.bias_vy = w.odometry.bias_omega = 0.0;
  w.odometry.start_at_truth = true;
  w.faults.odometry_slip = {{{1.0, 1.0}, 1.5}};
  const Recorder rec = run(w, 3.0);
  double vx;
  double vy;
  double omega;
  w.trajectory.body_velocity(vx, vy, omega);
  ASSERT_EQ(rec.odom.size(), 150u);
  int scaled = 0;
  for (const Odometry& o : rec.odom) {
    const double scale = in(o.utime, 1.0, 1.0) ? 1.5 : 1.0;
    scaled += scale != 1.0;
    EXPECT_NEAR(o.odom.vx, scale * vx, 1e-12);
    EXPECT_NEAR(o.odom.vy, scale * vy, 1e-12) << seconds(o.utime);
    EXPECT_NEAR(o.odom.omega, omega, 1e-12) << "the heading rate is not scaled";
  }
  EXPECT_EQ(scaled, 50);
  // Dead reckoning: exact up to the interval, 1.5 times the true path within it, the true rate after.
  const auto path = [&](std::size_t from, std::size_t to, bool truth) {
    double d = 0.0;
    for (std::size_t i = from + 1; i <= to; ++i) {
      const Pose2 a = truth ? w.trajectory.pose_at(seconds(rec.odom[i - 1].utime)) : rec.odom[i - 1].odom.pose;
      const Pose2 b = truth ? w.trajectory.pose_at(seconds(rec.odom[i].utime)) : rec.odom[i].odom.pose;
      d += std::hypot(b.x - a.x, b.y - a.y);
    }
    return d;
  };
  const Pose2 at_start = rec.odom[49].odom.pose;  // 0.98 s: the last sample before the slip
  const Pose2 truth_start = w.trajectory.pose_at(0.98);
  EXPECT_NEAR(at_start.x, truth_start.x, 1e-9);
  EXPECT_NEAR(at_start.y, truth_start.y, 1e-9);
  EXPECT_NEAR(path(49, 99, false) / path(49, 99, true), 1.5, 1e-6);
  EXPECT_NEAR(path(99, 149, false) / path(99, 149, true), 1.0, 1e-6);
  const Pose2 end = rec.odom.back().odom.pose;
  const Pose2 truth_end = w.trajectory.pose_at(seconds(rec.odom.back().utime));
  EXPECT_GT(std::hypot(end.x - truth_end.x, end.y - truth_end.y), 0.04) << "the slip left a drift of ~0.05 m";
}

TEST(SimulatorFaults, EveryFaultIsRecordedOnSimFaultAtItsStartAndEndInTimeOrder) {
  World w = arena();
  w.faults.dead_whiskers = {10};
  w.faults.board_offline = {{{0.5, 1.0}, 2}};
  w.faults.camera_blackout = {{1.0, 0.5}};
  w.faults.camera_freeze = {{1.7, 0.6}};
  w.faults.odometry_slip = {{{2.2, 5.0}, 1.2}};  // outlasts the run: no end
  w.faults.board_offline.push_back({{9.0, 1.0}, 4});  // after the run: never begins
  std::vector<FaultRecord> records;
  const Recorder rec = run(w, 3.0, &records);
  struct Expected {
    double t;
    FaultKind kind;
    bool active;
    int index;
    double value;
  };
  const Expected expected[] = {
      {0.0, FaultKind::DeadWhisker, true, 10, 0.0},   {0.5, FaultKind::BoardOffline, true, 2, 0.0},
      {1.0, FaultKind::CameraBlackout, true, -1, 0.0}, {1.5, FaultKind::BoardOffline, false, 2, 0.0},
      {1.5, FaultKind::CameraBlackout, false, -1, 0.0}, {1.7, FaultKind::CameraFreeze, true, -1, 0.0},
      {2.2, FaultKind::OdometrySlip, true, -1, 1.2},  {2.3, FaultKind::CameraFreeze, false, -1, 0.0},
  };
  ASSERT_EQ(rec.faults.size(), std::size(expected));
  for (std::size_t i = 0; i < rec.faults.size(); ++i) {
    const FaultEvent& e = rec.faults[i];
    EXPECT_EQ(e.utime, kStart + std::llround(expected[i].t * 1e6)) << i;
    EXPECT_EQ(e.kind, expected[i].kind) << i;
    EXPECT_EQ(e.active, expected[i].active) << i;
    EXPECT_EQ(e.index, expected[i].index) << i;
    EXPECT_EQ(e.value, expected[i].value) << i;
    const sim_fault_t m = to_lcm(e);
    EXPECT_EQ(m.utime, e.utime);
    EXPECT_EQ(m.active, e.active);
    EXPECT_EQ(m.index, e.index);
    EXPECT_EQ(m.value, e.value);
  }
  EXPECT_EQ(to_lcm(rec.faults[0]).kind, sim_fault_t::KIND_DEAD_WHISKER);
  EXPECT_EQ(to_lcm(rec.faults[1]).kind, sim_fault_t::KIND_BOARD_OFFLINE);
  EXPECT_EQ(to_lcm(rec.faults[2]).kind, sim_fault_t::KIND_CAMERA_BLACKOUT);
  EXPECT_EQ(to_lcm(rec.faults[5]).kind, sim_fault_t::KIND_CAMERA_FREEZE);
  EXPECT_EQ(to_lcm(rec.faults[6]).kind, sim_fault_t::KIND_ODOMETRY_SLIP);
  for (std::size_t i = 1; i < rec.times.size(); ++i) ASSERT_LE(rec.times[i - 1], rec.times[i]) << i;
  ASSERT_EQ(records.size(), 6u);
  EXPECT_EQ(records[0].affected, 1500) << "the dead whisker, every sample";
  EXPECT_EQ(records[1].affected, 500) << "board 2, one second";
  EXPECT_EQ(records[2].began_utime, -1) << "board 4 offline after the run";
  EXPECT_EQ(records[3].affected, 3) << "frames due at 1.0, 1.2, 1.4 s withheld";
  EXPECT_EQ(records[4].affected, 3) << "frames due at 1.8, 2.0, 2.2 s repeated";
  EXPECT_EQ(records[5].ended_utime, -1) << "the slip outlasts the run";
  EXPECT_EQ(records[5].affected, 40);
}

TEST(SimulatorFaults, AWorldWithFaultsGivesTheSameOutputsForTheSameSeed) {
  World w = arena();
  w.faults.dead_whiskers = {1};
  w.faults.board_offline = {{{0.5, 1.0}, 3}};
  w.faults.camera_freeze = {{0.3, 0.6}};
  const Recorder a = run(w, 2.0);
  const Recorder b = run(w, 2.0);
  EXPECT_EQ(a.times, b.times);
  ASSERT_EQ(a.samples.size(), b.samples.size());
  for (std::size_t i = 0; i < a.samples.size(); ++i) ASSERT_EQ(a.samples[i].deflection_x, b.samples[i].deflection_x);
}

// ---- a kidnap ----

// True contact onsets on a tactile landmark (not a wall) in [from_s, to_s).
int onsets_on_objects(const Recorder& rec, double from_s, double to_s = 1e9) {
  int n = 0;
  for (const ContactTruth::Point& p : rec.contacts) n += p.solid >= 0 && seconds(p.utime) >= from_s && seconds(p.utime) < to_s;
  return n;
}

TEST(SimulatorKidnap, GroundTruthJumpsToTheNewPlaceWhileOdometryGoesOnAsIfNothingHappened) {
  World w = arena();
  w.odometry.start_at_truth = true;
  const Recorder clean = run(w, 3.0);
  const double to = deg_to_rad(264.0);
  w.faults.kidnap = {{1.0, to}};
  std::vector<FaultRecord> records;
  const Recorder rec = run(w, 3.0, &records);
  ASSERT_EQ(rec.truth.size(), 150u);
  const double rate = w.trajectory.speed / w.trajectory.radius;  // rad/s, counter-clockwise
  for (const auto& [utime, pose] : rec.truth) {
    const double t = seconds(utime);
    const double angle = t < 1.0 - 1e-9 ? deg_to_rad(84.0) + rate * t : to + rate * (t - 1.0);
    ASSERT_NEAR(pose.x, std::cos(angle), 1e-9) << t;
    ASSERT_NEAR(pose.y, std::sin(angle), 1e-9) << t;
    ASSERT_NEAR(angle_diff(pose.theta, angle), 0.0, 1e-9) << "facing outwards as it would there, " << t;
  }
  const Pose2& before = rec.truth[49].second;  // 0.98 s
  const Pose2& after = rec.truth[50].second;   // 1.00 s
  EXPECT_GT(std::hypot(after.x - before.x, after.y - before.y), 1.9) << "put down across the circle";
  ASSERT_EQ(rec.odom.size(), clean.odom.size());
  for (std::size_t i = 0; i < rec.odom.size(); ++i) {
    ASSERT_EQ(rec.odom[i].odom.pose.x, clean.odom[i].odom.pose.x) << "odometry does not see the kidnap, " << i;
    ASSERT_EQ(rec.odom[i].odom.pose.y, clean.odom[i].odom.pose.y) << i;
    ASSERT_EQ(rec.odom[i].odom.pose.theta, clean.odom[i].odom.pose.theta) << i;
    ASSERT_EQ(rec.odom[i].odom.vy, clean.odom[i].odom.vy) << i;
  }
  // Recorded once, as it happens, with the pose the robot was put down at.
  ASSERT_EQ(rec.faults.size(), 1u);
  const FaultEvent& e = rec.faults[0];
  EXPECT_EQ(e.kind, FaultKind::Kidnap);
  EXPECT_TRUE(e.active);
  EXPECT_EQ(e.utime, kStart + 1'000'000);
  EXPECT_EQ(e.pose.x, after.x);
  EXPECT_EQ(e.pose.y, after.y);
  EXPECT_EQ(e.pose.theta, after.theta);
  const sim_fault_t m = to_lcm(e);
  EXPECT_EQ(m.kind, sim_fault_t::KIND_KIDNAP);
  EXPECT_TRUE(m.active);
  EXPECT_EQ(m.index, -1);
  EXPECT_EQ(m.value, 0.0);
  EXPECT_EQ(m.x, after.x);
  EXPECT_EQ(m.y, after.y);
  EXPECT_EQ(m.theta, after.theta);
  for (std::size_t i = 1; i < rec.times.size(); ++i) ASSERT_LE(rec.times[i - 1], rec.times[i]) << i;
  ASSERT_EQ(records.size(), 1u);
  EXPECT_EQ(records[0].kind, FaultKind::Kidnap);
  EXPECT_EQ(records[0].began_utime, kStart + 1'000'000);
  EXPECT_EQ(records[0].ended_utime, -1) << "an instant: no end";
}

TEST(SimulatorKidnap, TheCameraAndTheWhiskersFollowTheRobotWhereItWasPutDown) {
  // From a place with nothing to touch to just before the north box: the whiskers touch it only
  // because of the kidnap, and the camera sees what a run started there sees.
  World w = arena();
  w.trajectory.start_angle = deg_to_rad(200.0);
  const Recorder clean = run(w, 3.5);
  const double to = deg_to_rad(84.0);
  w.faults.kidnap = {{0.5, to}};
  const Recorder rec = run(w, 3.5);
  EXPECT_EQ(onsets_on_objects(clean, 0.0), 0) << "nothing to touch at 200-220 deg";
  EXPECT_EQ(onsets_on_objects(rec, 0.0, 0.5), 0) << "nor before the kidnap";
  EXPECT_GT(onsets_on_objects(rec, 0.5), 5) << "the box at the place put down at";
  World there = arena();
  there.trajectory.start_angle = to - 0.5 * w.trajectory.speed / w.trajectory.radius;  // there at 0.5 s
  const Recorder started_there = run(there, 3.5);
  ASSERT_EQ(rec.frames.size(), started_there.frames.size());
  ASSERT_EQ(rec.frames.size(), clean.frames.size());
  const auto mean_diff = [](const Frame& a, const Frame& b) {
    double d = 0.0;
    for (std::size_t i = 0; i < a.grey.size(); ++i) d += std::abs(int{a.grey[i]} - int{b.grey[i]});
    return d / static_cast<double>(a.grey.size());
  };
  for (std::size_t i = 0; i < rec.frames.size(); ++i) {
    const bool after = seconds(rec.frames[i].utime) >= 0.5;
    if (after) {
      EXPECT_LT(mean_diff(rec.frames[i], started_there.frames[i]), 0.5) << seconds(rec.frames[i].utime);
      EXPECT_GT(mean_diff(rec.frames[i], clean.frames[i]), 5.0) << seconds(rec.frames[i].utime);
    } else {
      EXPECT_TRUE(rec.frames[i].grey == clean.frames[i].grey) << seconds(rec.frames[i].utime);
    }
  }
}

// ---- the boards' CAN traffic ----

TEST(BoardTrafficFaults, AnOfflineBoardSendsNothingAndADeadWhiskerCarriesTheFaultBit) {
  BoardTrafficParams p;
  BoardTraffic t(p);
  std::vector<CanFrame> frames;
  rcp::WhiskerSample s;
  s.valid.fill(true);
  WhiskerHealth online;
  online.fault[5] = true;  // board 1, whisker k = 1
  s.valid[5] = false;
  WhiskerHealth offline = online;
  for (int w = 8; w < 12; ++w) offline.stale[w] = true;  // board 2
  std::map<uint32_t, int> count;
  std::vector<uint16_t> board2_seq;
  for (int i = 0; i < 250; ++i) {  // 0.5 s at 500 Hz; board 2 offline in [0.1, 0.3) s
    s.utime = kStart + 2000 * i;
    s.seq = i;
    frames.clear();
    t.add(s, i >= 50 && i < 150 ? offline : online, frames);
    for (const CanFrame& f : frames) {
      ++count[f.id];
      const wp::Decoded d = wp::decode_frame(f.id, f.fd, f.data, wp::BusMode::kFd);
      if (d.kind != wp::FrameKind::kSample) continue;
      for (int k = 0; k < wp::kWhiskersPerBoard; ++k) {
        ASSERT_EQ(d.sample.whiskers[k].fault, d.sample.board == 1 && k == 1) << "board " << d.sample.board;
      }
      if (d.sample.board == 2) board2_seq.push_back(d.sample.seq);
    }
  }
  EXPECT_EQ(count[0x182], 250);
  EXPECT_EQ(count[0x183], 150) << "no sample frames for 0.2 s";
  EXPECT_EQ(count[0x702], 5);
  EXPECT_EQ(count[0x703], 3) << "no heartbeats at 0.1 and 0.2 s";
  ASSERT_EQ(board2_seq.size(), 150u);
  EXPECT_EQ(board2_seq[49], 49);
  EXPECT_EQ(board2_seq[50], 150) << "it kept sampling: back online, its counter shows the gap";
}

TEST(LcmSinkFaults, StatusTellsAStaleWhiskerFromAFaultyOneAsWhiskerdDoes) {
  rcp::WhiskerSample s;
  s.valid.fill(true);
  WhiskerHealth h;
  h.stale[0] = true;
  h.fault[1] = true;
  h.stale[2] = h.fault[2] = true;  // a dead whisker on an offline board: its last frame had the fault bit
  s.valid[0] = s.valid[1] = s.valid[2] = false;
  s.valid[3] = false;  // invalid for no reason the simulator names: a fault
  const whisker_sample_t m = to_lcm(s, h, 1.0);
  EXPECT_EQ(m.status[0], whisker_sample_t::STATUS_STALE);
  EXPECT_EQ(m.status[1], whisker_sample_t::STATUS_FAULT);
  EXPECT_EQ(m.status[2], whisker_sample_t::STATUS_STALE | whisker_sample_t::STATUS_FAULT);
  EXPECT_EQ(m.status[3], whisker_sample_t::STATUS_FAULT);
  EXPECT_EQ(m.status[4], whisker_sample_t::STATUS_OK);
}

}  // namespace
}  // namespace whiskeye::sim
