// Contact detector: noise-floor learning, hysteresis, contact level, invalid whiskers.
#include <gtest/gtest.h>
#include <whiskeye/rcp/contact_detector.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

#include "helpers.h"

using namespace whiskeye::rcp;
using whiskeye::rcp::test::make_sample;

TEST(ContactDetector, UsesTheDefaultThresholdBeforeLearning) {
  ContactDetector d{DetectorParams{}};
  d.update(make_sample(1, 0.07, 0.0), false);
  EXPECT_FALSE(d.in_contact()[0]);
  d.update(make_sample(2, 0.09, 0.0), false);
  EXPECT_TRUE(d.in_contact()[0]);
  EXPECT_TRUE(d.onset()[0]);
  EXPECT_EQ(d.onsets()[0], 1);
}

TEST(ContactDetector, LearnsThresholdFromNoiseFloor) {
  DetectorParams p;
  ContactDetector d{p};
  std::mt19937_64 rng(7);
  std::normal_distribution<double> n(0.0, 0.01);
  std::vector<double> seen;
  for (int i = 0; i < 2000; ++i) {
    WhiskerSample s = make_sample(i + 1);
    for (int w = 0; w < kNumWhiskers; ++w) {
      s.deflection_x[w] = n(rng);
      s.deflection_y[w] = n(rng);
    }
    seen.push_back(std::hypot(s.deflection_x[5], s.deflection_y[5]));
    d.update(s, true);
  }
  d.finish_learning();
  ASSERT_TRUE(d.learned());
  // Whisker 5's threshold is 4 x the 75 % quantile of what it saw (to one histogram bin).
  std::sort(seen.begin(), seen.end());
  const double q75 = seen[1500 - 1];
  const double bin = p.threshold_max / p.noise_factor / 256.0;
  EXPECT_GE(d.threshold()[5], 4.0 * q75);
  EXPECT_LE(d.threshold()[5], 4.0 * (q75 + bin));
  // Rayleigh with sigma 0.01: q75 = 0.01665 -> about 0.067, above the 0.04 minimum.
  EXPECT_NEAR(d.threshold()[5], 0.0666, 0.004);
}

TEST(ContactDetector, ContactsWhileLearningDoNotInflateTheThreshold) {
  DetectorParams p;
  std::mt19937_64 rng(3);
  std::normal_distribution<double> n(0.0, 0.01);
  ContactDetector clean{p};
  ContactDetector touched{p};
  for (int i = 0; i < 1000; ++i) {
    WhiskerSample s = make_sample(i + 1);
    for (int w = 0; w < kNumWhiskers; ++w) {
      s.deflection_x[w] = n(rng);
      s.deflection_y[w] = n(rng);
    }
    clean.update(s, true);
    // Every 200 samples a contact ramps up through the default threshold to 0.19: its rising edge
    // below the threshold is learned from, the rest is not.
    if (i % 200 < 20) s.deflection_x[0] = -0.01 * (i % 200);
    touched.update(s, true);
  }
  clean.finish_learning();
  touched.finish_learning();
  EXPECT_NEAR(touched.threshold()[0], clean.threshold()[0], 0.1 * clean.threshold()[0]);
}

TEST(ContactDetector, LearnedThresholdIsClampedToMinimum) {
  DetectorParams p;
  ContactDetector d{p};
  for (int i = 0; i < 500; ++i) d.update(make_sample(i + 1, 0.001 * (i % 3), 0.0), true);
  d.finish_learning();
  EXPECT_DOUBLE_EQ(d.threshold()[0], p.threshold_min);
}

TEST(ContactDetector, KeepsDefaultWhenTooFewSamplesWereLearned) {
  DetectorParams p;
  ContactDetector d{p};
  for (int i = 0; i < 10; ++i) d.update(make_sample(i + 1, 0.001, 0.0), true);
  d.finish_learning();
  EXPECT_DOUBLE_EQ(d.threshold()[0], p.default_threshold);
}

TEST(ContactDetector, HysteresisHoldsContactUntilBelowReleaseLevel) {
  DetectorParams p;  // default threshold 0.08, release at 0.6 * 0.08 = 0.048
  ContactDetector d{p};
  d.update(make_sample(1, 0.0, 0.1), false);
  EXPECT_TRUE(d.in_contact()[3]);
  d.update(make_sample(2, 0.0, 0.06), false);
  EXPECT_TRUE(d.in_contact()[3]);
  EXPECT_FALSE(d.onset()[3]);
  d.update(make_sample(3, 0.0, 0.05), false);
  EXPECT_TRUE(d.in_contact()[3]);
  d.update(make_sample(4, 0.0, 0.045), false);
  EXPECT_FALSE(d.in_contact()[3]);
  d.update(make_sample(5, 0.0, 0.07), false);
  EXPECT_FALSE(d.in_contact()[3]);
  EXPECT_EQ(d.onsets()[3], 1);
}

TEST(ContactDetector, ContactLevelIsGainTimesExcessClippedToOne) {
  ContactDetector d{DetectorParams{}};
  d.update(make_sample(1, -0.12, 0.0), false);
  EXPECT_NEAR(d.level()[0], 5.0 * (0.12 - 0.08), 1e-12);
  d.update(make_sample(2, -0.6, 0.0), false);
  EXPECT_DOUBLE_EQ(d.level()[0], 1.0);
  d.update(make_sample(3, 0.0, 0.0), false);
  EXPECT_DOUBLE_EQ(d.level()[0], 0.0);
}

TEST(ContactDetector, InvalidWhiskerKeepsItsState) {
  ContactDetector d{DetectorParams{}};
  d.update(make_sample(1, 0.2, 0.0), false);
  WhiskerSample s = make_sample(2, 0.0, 0.0);
  s.valid[0] = false;
  d.update(s, false);
  EXPECT_TRUE(d.in_contact()[0]);
  EXPECT_FALSE(d.in_contact()[1]);
}

TEST(ContactDetector, DoesNotLearnFromContacts) {
  DetectorParams p;
  ContactDetector d{p};
  for (int i = 0; i < 1000; ++i) d.update(make_sample(i + 1, (i % 100 < 10) ? 0.5 : 0.001, 0.0), true);
  d.finish_learning();
  EXPECT_DOUBLE_EQ(d.threshold()[0], p.threshold_min);
}
