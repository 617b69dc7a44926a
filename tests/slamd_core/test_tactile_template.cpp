// Tactile template: contact estimation from θ and deflection, PFH invariance, SDA.
#include "whiskeye/slam/tactile_template.h"

#include "synthetic.h"

#include <gtest/gtest.h>

#include <cstring>
#include <limits>
#include <random>
#include <string>

namespace whiskeye::slam {
namespace {

double dist(const Vec3& a, const Vec3& b) { return std::sqrt((a.x - b.x) * (a.x - b.x) + (a.y - b.y) * (a.y - b.y) + (a.z - b.z) * (a.z - b.z)); }

TEST(ContactEstimation, RecoversContactAngleRadiusAndPointFromNoisyDeflection) {
  const RobotGeometry g = default_robot_geometry();
  const std::vector<test::SyntheticContact> truth = {
      {0, 0.10, 0.04}, {5, -0.10, 0.05}, {9, 0.30, 0.07}, {14, 0.00, 0.09}, {20, 0.20, 0.15}, {23, 0.35, 0.10}};
  const WhiskCycleInput cycle = test::whisk_cycle(g, truth, 0.003, 11);
  const TactileParams p;
  const std::vector<ContactEstimate> est = estimate_contacts(cycle, g, p);
  ASSERT_EQ(est.size(), truth.size());
  for (size_t i = 0; i < truth.size(); ++i) {
    SCOPED_TRACE(truth[i].whisker);
    EXPECT_EQ(est[i].whisker, truth[i].whisker);
    EXPECT_TRUE(est[i].fitted);
    EXPECT_NEAR(est[i].theta_contact, truth[i].theta_contact, 0.03);
    EXPECT_NEAR(est[i].radius, truth[i].radius, 0.1 * truth[i].radius);
    const Vec3 p_true = g.whisker_point(truth[i].whisker, truth[i].theta_contact, truth[i].radius);
    EXPECT_LT(dist(est[i].p_contact_in_head, p_true), 0.006);
  }
}

TEST(ContactEstimation, RemovesTheWhiskingSpeedTerm) {
  // The simulator's plant adds −0.004·θ̇ to x (θ̇ up to 4.4 rad/s here): calibrated out, the fit is
  // as good as without it; ignored, free-whisking whiskers cross the noise floor.
  const RobotGeometry g = default_robot_geometry();
  const std::vector<test::SyntheticContact> truth = {{2, 0.15, 0.04}, {13, 0.05, 0.06}, {21, 0.25, 0.12}};
  const WhiskCycleInput cycle = test::whisk_cycle(g, truth, 0.003, 14, 0, 500, 0.01);
  TactileParams p;
  p.speed_gain = 0.01;
  const std::vector<ContactEstimate> est = estimate_contacts(cycle, g, p);
  ASSERT_EQ(est.size(), truth.size());
  for (size_t i = 0; i < truth.size(); ++i) {
    EXPECT_NEAR(est[i].theta_contact, truth[i].theta_contact, 0.03);
    EXPECT_NEAR(est[i].radius, truth[i].radius, 0.1 * truth[i].radius);
  }
  p.speed_gain = 0.0;
  EXPECT_GT(estimate_contacts(cycle, g, p).size(), truth.size());
}

// A cycle whose every sample measured every whisker is computed sample by sample, all whiskers side
// by side; any other cycle whisker by whisker over its valid samples. A lost sample (valid 0) or a
// whisker not measured in one (NaN) leaves the other samples' traces alone, so inserting such a
// sample must give the same template to the bit, with and without the speed term and flags.
TEST(ContactEstimation, AllMeasuredCyclesGiveWhatTheWhiskerByWhiskerPathGives) {
  const RobotGeometry g = default_robot_geometry();
  const std::vector<test::SyntheticContact> truth = {{2, 0.15, 0.04}, {13, 0.05, 0.06}, {21, 0.25, 0.12}, {7, -0.1, 0.08}};
  const WhiskCycleInput cycle = test::whisk_cycle(g, truth, 0.003, 14, 0, 500, 0.01);
  const auto same = [](const TactileTemplate& a, const TactileTemplate& b) {
    return a.num_contacts == b.num_contacts && a.pfh == b.pfh && a.sensed == b.sensed &&
           std::memcmp(a.sda.data(), b.sda.data(), sizeof(float) * a.sda.size()) == 0;
  };
  for (const double speed_gain : {0.0, 0.01}) {
    for (const bool flags : {false, true}) {
      TactileParams p;
      p.speed_gain = speed_gain;
      p.use_contact_flags = flags;
      const TactileTemplate fast = make_tactile_template(cycle, g, p);
      ASSERT_GT(fast.num_contacts, 2);
      for (const size_t at : {size_t{0}, size_t{137}, cycle.samples.size()}) {
        SCOPED_TRACE("speed gain " + std::to_string(speed_gain) + ", flags " + std::to_string(flags) + ", at " + std::to_string(at));
        WhiskCycleInput lost = cycle;
        WhiskSample gap = cycle.samples[std::min(at, cycle.samples.size() - 1)];
        gap.valid = false;
        lost.samples.insert(lost.samples.begin() + static_cast<std::ptrdiff_t>(at), gap);
        EXPECT_TRUE(same(make_tactile_template(lost, g, p), fast)) << "a lost sample";
        // Every whisker NaN in one sample: no whisker measured it, so the sensed mask stays.
        WhiskCycleInput unmeasured = cycle;
        WhiskSample nan = gap;
        nan.valid = true;
        nan.theta.fill(std::numeric_limits<float>::quiet_NaN());
        nan.deflection_x.fill(std::numeric_limits<float>::quiet_NaN());
        nan.deflection_y.fill(std::numeric_limits<float>::quiet_NaN());
        unmeasured.samples.insert(unmeasured.samples.begin() + static_cast<std::ptrdiff_t>(at), nan);
        EXPECT_TRUE(same(make_tactile_template(unmeasured, g, p), fast)) << "a sample measuring no whisker";
      }
    }
  }
}

TEST(ContactEstimation, NoiseBelowTheFloorIsNoContact) {
  const RobotGeometry g = default_robot_geometry();
  const WhiskCycleInput cycle = test::whisk_cycle(g, {}, 0.01, 12);
  const TactileTemplate t = make_tactile_template(cycle, g, TactileParams{});
  EXPECT_EQ(t.num_contacts, 0);
  EXPECT_FALSE(t.has_contact());
  for (uint16_t v : t.pfh) EXPECT_EQ(v, 0);
  for (float v : t.sda) EXPECT_EQ(v, 0.0f);
}

TEST(ContactEstimation, DiagonalDeflectionJustAboveTheFloorIsContact) {
  // |deflection| is compared with the floor as a 2-D magnitude: equal x and y components of 1 %
  // above floor/√2 are above it (the cheap max-component pre-check must not drop them), 1 % below
  // are not.
  const RobotGeometry g = default_robot_geometry();
  WhiskCycleInput cycle = test::whisk_cycle(g, {}, 0.0, 13);
  TactileParams p;
  p.speed_gain = 0.0;
  const double component = p.contact_threshold / std::sqrt(2.0);
  for (WhiskSample& s : cycle.samples) {
    s.deflection_x[3] = s.deflection_y[3] = static_cast<float>(1.01 * component);
    s.deflection_x[7] = s.deflection_y[7] = static_cast<float>(0.99 * component);
  }
  const std::vector<ContactEstimate> est = estimate_contacts(cycle, g, p);
  ASSERT_EQ(est.size(), 1u);
  EXPECT_EQ(est[0].whisker, 3);
}

TEST(ContactEstimation, RadiusIsClampedToTheWhiskerLength) {
  const RobotGeometry g = default_robot_geometry();
  // A "contact" beyond the tip (weak slope) must not be placed past the whisker's end.
  const WhiskCycleInput cycle = test::whisk_cycle(g, {{3, -0.3, 0.5}}, 0.0, 13);
  TactileParams p;
  p.contact_threshold = 0.005;
  const std::vector<ContactEstimate> est = estimate_contacts(cycle, g, p);
  ASSERT_EQ(est.size(), 1u);
  EXPECT_LE(est[0].radius, g.whiskers[3].length);
}

std::vector<Vec3> random_cloud(uint32_t seed, int n) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-0.1, 0.1);
  std::vector<Vec3> pts;
  for (int i = 0; i < n; ++i) {
    // A curved surface patch (not a plane, so normals vary) a little in front of the viewpoint.
    const double y = u(rng), z = u(rng);
    pts.push_back({0.2 + 3.0 * y * y - 2.0 * z * z + 0.2 * y * z, y, z});
  }
  return pts;
}


TEST(Pfh, UnchangedUnderARigidMotionOfTheCloud) {
  const std::vector<Vec3> cloud = random_cloud(21, 16);
  // Rotation about an arbitrary axis (Rodrigues) and a translation, applied to points and viewpoint.
  const double ax = 0.3, ay = -0.5, az = 0.8, ang = 1.1;
  const double nrm = std::sqrt(ax * ax + ay * ay + az * az);
  const double kx = ax / nrm, ky = ay / nrm, kz = az / nrm, c = std::cos(ang), s = std::sin(ang), t = 1 - c;
  const double R[3][3] = {{t * kx * kx + c, t * kx * ky - s * kz, t * kx * kz + s * ky},
                          {t * kx * ky + s * kz, t * ky * ky + c, t * ky * kz - s * kx},
                          {t * kx * kz - s * ky, t * ky * kz + s * kx, t * kz * kz + c}};
  auto move = [&](const Vec3& p) {
    return Vec3{R[0][0] * p.x + R[0][1] * p.y + R[0][2] * p.z + 0.7, R[1][0] * p.x + R[1][1] * p.y + R[1][2] * p.z - 1.3,
                R[2][0] * p.x + R[2][1] * p.y + R[2][2] * p.z + 0.4};
  };
  std::vector<Vec3> moved;
  for (const Vec3& p : cloud) moved.push_back(move(p));
  const auto a = compute_pfh(cloud, Vec3{}, 5);
  const auto b = compute_pfh(moved, move(Vec3{}), 5);
  double sum = 0.0, l1 = 0.0;
  int nonzero = 0;
  for (int i = 0; i < kPfhBins; ++i) {
    sum += a[static_cast<size_t>(i)];
    l1 += std::abs(a[static_cast<size_t>(i)] - b[static_cast<size_t>(i)]);
    nonzero += a[static_cast<size_t>(i)] > 0.0;
  }
  EXPECT_NEAR(sum, 1.0, 1e-12);
  EXPECT_GT(nonzero, 3);  // a curved patch spreads over several bins
  EXPECT_LT(l1, 1e-12);
}

TEST(Pfh, TellsAPlaneFromACorner) {
  std::vector<Vec3> plane, corner;
  for (int i = 0; i < 4; ++i)
    for (int j = 0; j < 4; ++j) {
      plane.push_back({0.2, -0.06 + 0.04 * i, -0.06 + 0.04 * j});
      const double y = -0.06 + 0.04 * i;
      corner.push_back({0.2 - std::abs(y), y, -0.06 + 0.04 * j});
    }
  const auto a = compute_pfh(plane, Vec3{}, 5);
  const auto b = compute_pfh(corner, Vec3{}, 5);
  double l1 = 0.0;
  for (int i = 0; i < kPfhBins; ++i) l1 += std::abs(a[static_cast<size_t>(i)] - b[static_cast<size_t>(i)]);
  EXPECT_GT(l1, 0.3);
  // All pairs of a plane share one feature (α = φ = θ = 0): the centre bin.
  EXPECT_NEAR(a[(2 * kPfhBinsPerDim + 2) * kPfhBinsPerDim + 2], 1.0, 1e-12);
}

TEST(Pfh, IsAllZeroWithFewerThanThreePoints) {
  const auto h = compute_pfh({{0.1, 0, 0}, {0.2, 0, 0}}, Vec3{}, 5);
  for (double v : h) EXPECT_EQ(v, 0.0);
}

TEST(Pfh, PointHistogramAlternativeUsesFixedBinEdges) {
  TactileParams p;
  p.histogram_min = {0.0, 0.0, 0.0};
  p.histogram_max = {1.0, 1.0, 1.0};
  const auto h = compute_point_histogram({{0.05, 0.05, 0.05}, {0.05, 0.05, 0.05}, {0.95, 0.5, 0.05}, {2.0, 2.0, 2.0}}, p);
  EXPECT_DOUBLE_EQ(h[0], 0.5);
  EXPECT_DOUBLE_EQ(h[(4 * 5 + 2) * 5 + 0], 0.25);
  EXPECT_DOUBLE_EQ(h[124], 0.25);  // outside the bounds: the edge bin, never a moving edge
}

TEST(Sda, OfASyntheticRampIsItsSlope) {
  WhiskCycleInput c;
  for (int i = 0; i < 500; ++i) {
    WhiskSample s;
    s.utime = 1000000 + i * 2000;  // 500 Hz
    const double t = i * 0.002;
    // Whisker 7: 0 until 0.2 s, then a ramp of 1.25 /s (split over x and y) to 0.6 s, then decays.
    double m = 0.0;
    if (t >= 0.2 && t <= 0.6) m = 1.25 * (t - 0.2);
    if (t > 0.6) m = std::max(0.0, 0.5 - 2.0 * (t - 0.6));
    s.deflection_x[7] = static_cast<float>(0.6 * m);
    s.deflection_y[7] = static_cast<float>(0.8 * m);
    c.samples.push_back(s);
  }
  const std::array<float, kSdaSize> sda = compute_sda(c, TactileParams{});
  EXPECT_NEAR(sda[7], 1.25, 1e-3);
  for (int w = 0; w < kNumWhiskers; ++w)
    if (w != 7) {
      EXPECT_EQ(sda[static_cast<size_t>(w)], 0.0f);
    }
}

TEST(Sda, AllTwentyFourWhiskersAreFilled) {
  // The original code lost the 24th SDA value; here every whisker, including the last, counts.
  const RobotGeometry g = default_robot_geometry();
  std::vector<test::SyntheticContact> all;
  for (int w = 0; w < kNumWhiskers; ++w) all.push_back({w, 0.1, 0.5 * g.whiskers[static_cast<size_t>(w)].length});
  const TactileTemplate t = make_tactile_template(test::whisk_cycle(g, all, 0.0, 1), g, TactileParams{});
  EXPECT_EQ(t.num_contacts, kNumWhiskers);
  for (int w = 0; w < kNumWhiskers; ++w) EXPECT_GT(t.sda[static_cast<size_t>(w)], 0.0f) << w;
}

}  // namespace
}  // namespace whiskeye::slam
