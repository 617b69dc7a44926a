// Plant model: PD joint tracking, cantilever contact deflection, reach, noise, speed term.
#include <gtest/gtest.h>
#include <whiskeye/rcp/plant.h>

#include <cmath>

using namespace whiskeye;
using namespace whiskeye::rcp;

namespace {

constexpr int64_t kPeriod = 2000;

// Holds a constant command for `steps` periods; returns the last sample.
WhiskerSample hold(WhiskerPlant& plant, double command, int steps, int64_t& utime) {
  PerWhisker<double> cmd;
  cmd.fill(command);
  WhiskerSample s;
  for (int i = 0; i < steps; ++i) s = plant.step(utime += kPeriod, cmd);
  return s;
}

PlantParams quiet() {
  PlantParams p;
  p.noise_sigma = 0.0;
  p.theta_noise_sigma = 0.0;
  return p;
}

}  // namespace

TEST(WhiskerPlant, JointTracksACommandStep) {
  WhiskerPlant plant(quiet(), 1);
  int64_t t = 0;
  hold(plant, 0.3, 250, t);  // 0.5 s at 20 Hz bandwidth: settled
  EXPECT_NEAR(plant.true_state()[0].theta, 0.3, 1e-4);
  EXPECT_NEAR(plant.true_state()[0].theta_dot, 0.0, 1e-3);
}

TEST(WhiskerPlant, JointRespectsItsRange) {
  WhiskerPlant plant(quiet(), 1);
  int64_t t = 0;
  hold(plant, 3.0, 100, t);
  EXPECT_LE(plant.true_state()[0].theta, deg_to_rad(60.0) + 1e-12);
}

TEST(WhiskerPlant, DeflectionGrowsWithBendingAfterContact) {
  PlantParams p = quiet();
  p.speed_gain = 0.0;
  p.contact_load = 0.0;
  WhiskerPlant plant(p, 1);
  plant.set_obstacle(0, Obstacle{0.0, 0.03});
  int64_t t = 0;
  hold(plant, -0.1, 250, t);
  EXPECT_FALSE(plant.true_state()[0].in_contact);
  EXPECT_NEAR(plant.true_state()[0].contact_deflection, 0.0, 1e-12);
  hold(plant, 0.1, 250, t);
  const double d1 = plant.true_state()[0].contact_deflection;
  EXPECT_TRUE(plant.true_state()[0].in_contact);
  hold(plant, 0.2, 250, t);
  const double d2 = plant.true_state()[0].contact_deflection;
  EXPECT_NEAR(d2 / d1, 2.0, 1e-3);  // linear in bending theta - contact_angle
  // gain * bending * length / r
  EXPECT_NEAR(d2, 0.6 * 0.2 * 0.0604 / 0.03, 1e-3);
  // Pushed back: along -x by default.
  const WhiskerSample s = hold(plant, 0.2, 1, t);
  EXPECT_NEAR(s.deflection_x[0], -d2, 1e-4);
  EXPECT_NEAR(s.deflection_y[0], 0.0, 1e-12);
}

TEST(WhiskerPlant, ContactNearerTheBaseBendsTheBaseMore) {
  PlantParams p = quiet();
  p.contact_load = 0.0;
  WhiskerPlant plant(p, 1);
  const int near = whisker_index(3, 0);  // 171.7 mm whisker
  const int far = whisker_index(3, 1);
  plant.set_obstacle(near, Obstacle{0.0, 0.04});
  plant.set_obstacle(far, Obstacle{0.0, 0.16});
  int64_t t = 0;
  hold(plant, 0.15, 300, t);
  EXPECT_NEAR(plant.true_state()[near].contact_deflection / plant.true_state()[far].contact_deflection, 4.0, 1e-6);
}

TEST(WhiskerPlant, ObstacleBeyondTheWhiskerIsNotTouched) {
  WhiskerPlant plant(quiet(), 1);
  plant.set_obstacle(0, Obstacle{0.0, 0.07});  // row 0 whisker is 60.4 mm
  plant.set_obstacle(18, Obstacle{0.0, 0.07});  // row 3 whisker is 171.7 mm
  int64_t t = 0;
  hold(plant, 0.3, 200, t);
  EXPECT_FALSE(plant.true_state()[0].in_contact);
  EXPECT_TRUE(plant.true_state()[18].in_contact);
}

TEST(WhiskerPlant, NoiseIsSeededAndHasTheConfiguredSpread) {
  PlantParams p;
  p.speed_gain = 0.0;
  WhiskerPlant a(p, 42);
  WhiskerPlant b(p, 42);
  WhiskerPlant c(p, 43);
  int64_t ta = 0, tb = 0, tc = 0;
  double sum2 = 0.0;
  int n = 0;
  bool differs = false;
  for (int i = 0; i < 400; ++i) {
    const WhiskerSample sa = hold(a, p.initial_theta, 1, ta);
    const WhiskerSample sb = hold(b, p.initial_theta, 1, tb);
    const WhiskerSample sc = hold(c, p.initial_theta, 1, tc);
    EXPECT_EQ(sa.deflection_x, sb.deflection_x);
    differs = differs || sa.deflection_x != sc.deflection_x;
    for (int w = 0; w < kNumWhiskers; ++w) {
      sum2 += sa.deflection_x[w] * sa.deflection_x[w];
      ++n;
    }
  }
  EXPECT_TRUE(differs);
  EXPECT_NEAR(std::sqrt(sum2 / n), p.noise_sigma, 0.1 * p.noise_sigma);
}

TEST(WhiskerPlant, WhiskingSpeedBendsTheWhiskerAgainstItsMotion) {
  PlantParams p = quiet();
  WhiskerPlant plant(p, 1);
  int64_t t = 0;
  hold(plant, p.initial_theta, 10, t);
  const WhiskerSample s = hold(plant, 0.5, 5, t);  // fast protraction
  EXPECT_GT(plant.true_state()[0].theta_dot, 1.0);
  EXPECT_NEAR(s.deflection_x[0], -p.speed_gain * plant.true_state()[0].theta_dot, 1e-12);
}

TEST(WhiskerPlant, SequenceAndTimeComeFromTheCaller) {
  WhiskerPlant plant(quiet(), 1);
  PerWhisker<double> cmd{};
  const WhiskerSample a = plant.step(1000, cmd);
  const WhiskerSample b = plant.step(3000, cmd);
  EXPECT_EQ(a.utime, 1000);
  EXPECT_EQ(b.utime, 3000);
  EXPECT_EQ(b.seq, a.seq + 1);
  EXPECT_TRUE(b.valid[23]);
}
