// The closed-loop simulation: rates, time order, contacts at tactile landmarks, RCP reacting.
#include "sim_test_util.h"

#include "whiskeye/sim/simulator.h"

#include <gtest/gtest.h>

#include <cmath>
#include <map>

namespace whiskeye::sim {
namespace {

struct Recorder : SimSink {
  std::map<std::string, int> count;
  std::vector<int64_t> times;
  std::vector<ContactTruth> truths;
  std::vector<rcp::WhiskCycle> cycles;
  double min_ceiling = 1e9;
  double max_deflection = 0.0;
  void tick(const char* ch, int64_t t) {
    ++count[ch];
    times.push_back(t);
  }
  void whisker_sample(const rcp::WhiskerSample& s, const WhiskerHealth&) override {
    tick("WHISKER_SAMPLE", s.utime);
    for (int w = 0; w < rcp::kNumWhiskers; ++w) max_deflection = std::max(max_deflection, std::hypot(s.deflection_x[w], s.deflection_y[w]));
  }
  void rcp_state(const rcp::ControlOutput& o) override {
    tick("RCP_STATE", o.utime);
    for (double c : o.theta_ceiling) min_ceiling = std::min(min_ceiling, c);
  }
  void whisk_cycle(const rcp::WhiskCycle& c) override {
    tick("WHISK_CYCLE", c.utime_end);
    cycles.push_back(c);
  }
  void contact_truth(const ContactTruth& t) override {
    tick("SIM_CONTACT_TRUTH", t.utime);
    truths.push_back(t);
  }
  void odometry(int64_t u, int64_t, const OdometrySample&) override { tick("ODOMETRY", u); }
  void ground_truth(int64_t u, const Pose2&) override { tick("GROUND_TRUTH", u); }
  void camera(int64_t u, int64_t, const std::vector<uint8_t>& g, int w, int h) override {
    tick("CAMERA", u);
    EXPECT_EQ(g.size(), static_cast<std::size_t>(w * h));
  }
  void fault(const FaultEvent& e) override { tick("SIM_FAULT", e.utime); }
};

World arena(double start_deg) {
  World w = load_world_file(test::source_path("config/worlds/aliased_arena.yaml"));
  w.trajectory.start_angle = deg_to_rad(start_deg);
  return w;
}

Recorder run(const World& world, double seconds, uint64_t seed = 1) {
  SimParams p;
  p.duration = seconds;
  p.seed = seed;
  Simulator sim(world, default_robot_geometry(), rcp::ControllerParams{}, rcp::PlantParams{}, p);
  Recorder rec;
  while (sim.step(rec)) {
  }
  return rec;
}

TEST(Simulator, ChannelRatesAreThoseOfTheDrivers) {
  const Recorder rec = run(arena(180.0), 3.0);
  EXPECT_EQ(rec.count.at("WHISKER_SAMPLE"), 1500);  // 500 Hz
  EXPECT_EQ(rec.count.at("RCP_STATE"), 1500);       // 500 Hz
  EXPECT_EQ(rec.count.at("ODOMETRY"), 150);         // 50 Hz
  EXPECT_EQ(rec.count.at("GROUND_TRUTH"), 150);     // 50 Hz
  EXPECT_EQ(rec.count.at("CAMERA"), 15);            // 5 fps
  EXPECT_GE(rec.count.at("WHISK_CYCLE"), 2);        // 1 Hz (the first starts after the enable)
  EXPECT_EQ(rec.count.at("WHISK_CYCLE"), rec.count.at("SIM_CONTACT_TRUTH"));
}

TEST(Simulator, OutputsComeInTimeOrder) {
  const Recorder rec = run(arena(80.0), 3.0);
  for (std::size_t i = 1; i < rec.times.size(); ++i) ASSERT_LE(rec.times[i - 1], rec.times[i]) << i;
}

TEST(Simulator, NoContactWhereNoObjectIsWithinReach) {
  const Recorder rec = run(arena(180.0), 4.0);
  for (const ContactTruth& t : rec.truths) EXPECT_TRUE(t.points.empty()) << "cycle " << t.cycle;
  EXPECT_DOUBLE_EQ(rec.min_ceiling, rcp::ControllerParams{}.pattern.theta_max);
}

TEST(Simulator, PassingABoxGivesContactsOnItsSurfaceAndRcpReacts) {
  const World world = arena(84.0);  // box_north is at 90°: the robot passes it within 2 s
  const Recorder rec = run(world, 6.0);
  const RobotGeometry robot = default_robot_geometry();
  int points = 0;
  for (const ContactTruth& t : rec.truths) {
    for (const ContactTruth::Point& p : t.points) {
      ++points;
      // The head-frame point, back in the world at its time, lies on the box (within 5 mm).
      const double tt = static_cast<double>(p.utime - SimParams{}.start_utime) * 1e-6;
      const Pose2 head = compose(world.trajectory.pose_at(tt), robot.T_base_head);
      Point2 q;
      transform_point(head, p.p_in_head.x, p.p_in_head.y, q.x, q.y);
      const Solid& box = world.solids[1];
      ASSERT_EQ(box.name, "box_north");
      double best = 1e9;
      for (std::size_t i = 0; i < box.vertices.size(); ++i) {
        const Point2& a = box.vertices[i];
        const Point2& b = box.vertices[(i + 1) % box.vertices.size()];
        const double ex = b.x - a.x;
        const double ey = b.y - a.y;
        const double u = std::clamp(((q.x - a.x) * ex + (q.y - a.y) * ey) / (ex * ex + ey * ey), 0.0, 1.0);
        best = std::min(best, std::hypot(q.x - a.x - u * ex, q.y - a.y - u * ey));
      }
      EXPECT_LT(best, 0.005) << "whisker " << p.whisker;
      EXPECT_LE(robot.head_height + p.p_in_head.z, box.z1 + 1e-9);
    }
  }
  EXPECT_GT(points, 5);
  // The controller saw the contacts: some ceilings dropped below theta_max, cycles carry contacts.
  EXPECT_LT(rec.min_ceiling, rcp::ControllerParams{}.pattern.theta_max - 0.01);
  int contact_samples = 0;
  for (const rcp::WhiskCycle& c : rec.cycles) {
    for (const auto& s : c.samples) {
      for (bool b : s.contact) contact_samples += b;
    }
  }
  EXPECT_GT(contact_samples, 0);
  EXPECT_GT(rec.max_deflection, 0.04);
}

TEST(Simulator, SameSeedSameOutputsDifferentSeedDifferentNoise) {
  const Recorder a = run(arena(84.0), 3.0, 5);
  const Recorder b = run(arena(84.0), 3.0, 5);
  EXPECT_EQ(a.times, b.times);
  EXPECT_EQ(a.max_deflection, b.max_deflection);
  const Recorder c = run(arena(84.0), 3.0, 6);
  EXPECT_NE(a.max_deflection, c.max_deflection);
}

}  // namespace
}  // namespace whiskeye::sim
