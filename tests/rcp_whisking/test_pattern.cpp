// Pattern generator: the WhiskEye sine, cycle start at theta_min, waveforms, per-row phase.
#include <gtest/gtest.h>
#include <whiskeye/rcp/pattern.h>

#include <cmath>

using namespace whiskeye;
using namespace whiskeye::rcp;

TEST(Pattern, CycleStartsAtThetaMinAndPeaksAtThetaMax) {
  PatternGenerator g{PatternParams{}};
  EXPECT_DOUBLE_EQ(g.theta(0.0), deg_to_rad(-30.0));
  EXPECT_NEAR(g.theta(0.5), deg_to_rad(45.0), 1e-12);
  EXPECT_NEAR(g.theta(1.0), deg_to_rad(-30.0), 1e-12);
  EXPECT_TRUE(g.protracting(0.0));
  EXPECT_TRUE(g.protracting(0.49));
  EXPECT_FALSE(g.protracting(0.5));
  EXPECT_FALSE(g.protracting(0.99));
  EXPECT_TRUE(g.protracting(3.01));
}

TEST(Pattern, DefaultIsTheWhiskEyeSineShiftedToStartAtTheTrough) {
  // WhiskEye: x = 0.5 + 0.5 sin(2 pi f t); our cycle starts at its trough, t = -1/(4f).
  PatternGenerator g{PatternParams{}};
  const double tmin = deg_to_rad(-30.0);
  const double tmax = deg_to_rad(45.0);
  for (double phase = 0.0; phase < 2.0; phase += 0.013) {
    const double t = phase - 0.25;  // f = 1 Hz
    const double x = 0.5 + 0.5 * std::sin(kTwoPi * t);
    EXPECT_NEAR(g.theta(phase), tmin + x * (tmax - tmin), 1e-12) << phase;
  }
}

TEST(Pattern, ProtractionFractionMakesProtractionLonger) {
  PatternParams p;
  p.protraction_fraction = 0.7;
  PatternGenerator g{p};
  EXPECT_NEAR(g.excursion(0.7), 1.0, 1e-12);
  EXPECT_NEAR(g.excursion(0.35), 0.5, 1e-12);
  EXPECT_NEAR(g.excursion(0.85), 0.5, 1e-12);
  EXPECT_TRUE(g.protracting(0.69));
  EXPECT_FALSE(g.protracting(0.71));
  // Monotone up during protraction, down during retraction.
  for (double u = 0.0; u < 0.69; u += 0.01) EXPECT_LT(g.excursion(u), g.excursion(u + 0.01));
  for (double u = 0.7; u < 0.99; u += 0.01) EXPECT_GT(g.excursion(u), g.excursion(u + 0.01));
}

TEST(Pattern, TriangleWaveformIsLinear) {
  PatternParams p;
  p.waveform = Waveform::Triangle;
  PatternGenerator g{p};
  EXPECT_NEAR(g.excursion(0.25), 0.5, 1e-12);
  EXPECT_NEAR(g.excursion(0.1), 0.2, 1e-12);
  EXPECT_NEAR(g.excursion(0.9), 0.2, 1e-12);
}

TEST(Pattern, RowPhaseLeadsThatRow) {
  PatternParams p;
  p.row_phase = {0.0, 0.25, 0.0, 0.5};
  PatternGenerator g{p};
  EXPECT_DOUBLE_EQ(g.row_phase(0.1, 0), 0.1);
  EXPECT_DOUBLE_EQ(g.row_phase(0.1, 1), 0.35);
  EXPECT_DOUBLE_EQ(g.theta(g.row_phase(0.0, 3)), p.theta_max);
}
