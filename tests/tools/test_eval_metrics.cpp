// Unit tests of the Table I metrics on synthetic inputs whose answers can be computed by hand.
#include "whiskeye/eval/metrics.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace whiskeye::eval {
namespace {

constexpr int64_t kSecond = 1'000'000;

// The paper's trajectory: a 1 m radius circle around the origin, facing outwards, one revolution per
// `period_s`, sampled at 50 Hz.
Pose2 circle_pose(double t_s, double period_s, double phase = 0.0, double direction = 1.0) {
  const double a = phase + direction * kTwoPi * t_s / period_s;
  return {std::cos(a), std::sin(a), wrap_angle(a)};
}

std::vector<PoseSample> circle_gt(double duration_s, double period_s, double phase = 0.0,
                                  double direction = 1.0, double cx = 0.0, double cy = 0.0) {
  std::vector<PoseSample> out;
  for (int64_t u = 0; u <= static_cast<int64_t>(duration_s * kSecond); u += 20'000) {
    Pose2 p = circle_pose(static_cast<double>(u) / kSecond, period_s, phase, direction);
    p.x += cx;
    p.y += cy;
    out.push_back({u, p});
  }
  return out;
}

// An estimate in a map frame that sits at T_world_map in the world, otherwise exact.
std::vector<PoseSample> exact_estimate(const std::vector<PoseSample>& gt, const Pose2& T_world_map) {
  std::vector<PoseSample> out;
  for (const PoseSample& s : gt) out.push_back({s.utime, compose(inverse(T_world_map), s.pose)});
  return out;
}

ExperienceMap exact_chain_map(const GroundTruth& gt, const Pose2& T_world_map, int n, int64_t every_us) {
  ExperienceMap map;
  for (int i = 0; i < n; ++i) {
    const int64_t t = i * every_us;
    map.experiences.push_back({i, compose(inverse(T_world_map), *gt.at(t)), t, i % 2 == 0});
    if (i > 0) map.links.push_back({i - 1, i, false, {}});
  }
  return map;
}

// Each link judged by the truth at its ends' creation: the right ones (a 1 cm odometry error, a
// neighbour 0.2 m off), the wrong ones beyond 0.25 m or 15 degrees, kept or revoked.
TEST(Links, AreJudgedAgainstTheTruthAtTheirEndsCreationAndCountedKeptOrRevoked) {
  // The robot drives along x at 0.1 m/s, turning nothing; experience i made at i seconds.
  std::vector<PoseSample> samples;
  for (int i = 0; i <= 10; ++i) samples.push_back({i * 1'000'000, {0.1 * i, 0.0, 0.0}});
  const GroundTruth gt(samples);
  ExperienceMap map;
  for (int i = 0; i <= 10; ++i) map.experiences.push_back({i, {5.0, 5.0, 1.0}, i * 1'000'000, false});  // map poses unused
  map.links = {{0, 1, false, {0.11, 0.0, 0.0}},          // odometry, 1 cm off: right
               {1, 5, false, {0.2, 0.0, 0.0}},           // a neighbour: 0.2 m off, right
               {2, 9, false, {0.0, 0.0, 0.0}},           // 0.7 m off, kept: wrong
               {3, 8, true, {0.0, 0.0, 0.0}},            // 0.5 m off, revoked
               {4, 5, false, {0.1, 0.0, 0.3}},           // 17 degrees off: wrong
               {6, 7, true, {0.1, 0.0, 0.0}},            // right, revoked
               {6, 42, false, {0.0, 0.0, 0.0}}};         // no such experience: not judged
  const LinkJudgement j = judge_links(map, gt, EvalParams{});
  EXPECT_EQ(j.judged, 6u);
  EXPECT_EQ(j.wrong, 3u);
  EXPECT_EQ(j.wrong_kept, 2u);
  EXPECT_EQ(j.right_revoked, 1u);
  ASSERT_TRUE(j.worst_kept_m.has_value());
  EXPECT_NEAR(*j.worst_kept_m, 0.7, 1e-9);
}

TEST(GroundTruth, InterpolatesHeadingAcrossThePiWrap) {
  const GroundTruth gt({{0, {0.0, 0.0, kPi - 0.1}}, {100, {1.0, -2.0, -kPi + 0.1}}});
  const Pose2 mid = *gt.at(50);
  EXPECT_NEAR(mid.x, 0.5, 1e-12);
  EXPECT_NEAR(mid.y, -1.0, 1e-12);
  EXPECT_NEAR(std::abs(angle_diff(mid.theta, kPi)), 0.0, 1e-12);  // through pi, not through 0
  EXPECT_NEAR(gt.at(25)->theta, kPi - 0.05, 1e-12);
  EXPECT_NEAR(gt.at(75)->theta, -kPi + 0.05, 1e-12);
}

TEST(GroundTruth, ReturnsSamplesExactlyAndNothingOutsideItsRange) {
  const GroundTruth gt({{200, {2.0, 0.0, 0.0}}, {100, {1.0, 0.0, 0.5}}});  // unsorted on purpose
  EXPECT_EQ(gt.begin_utime(), 100);
  EXPECT_EQ(gt.end_utime(), 200);
  EXPECT_DOUBLE_EQ(gt.at(100)->theta, 0.5);
  EXPECT_DOUBLE_EQ(gt.at(200)->x, 2.0);
  EXPECT_FALSE(gt.at(99).has_value());
  EXPECT_FALSE(gt.at(201).has_value());
}

TEST(Lem, PerfectEstimateGivesZeroLemAndZeroEnm) {
  EvalInput in;
  in.ground_truth = circle_gt(20.0, 10.0);
  const GroundTruth gt(in.ground_truth);
  in.estimate = in.ground_truth;
  in.map = exact_chain_map(gt, Pose2{}, 20, kSecond / 2);
  const EvalResult r = evaluate(in, EvalParams{});
  ASSERT_TRUE(r.lem.has_value());
  EXPECT_EQ(r.lem->samples_used, in.estimate.size());
  EXPECT_NEAR(r.lem->position_m.rmse, 0.0, 1e-12);
  EXPECT_NEAR(r.lem->orientation_rad.rmse, 0.0, 1e-12);
  ASSERT_TRUE(r.enm.enm.has_value());
  EXPECT_EQ(r.enm.links_used, 19u);
  EXPECT_NEAR(*r.enm.enm, 0.0, 1e-20);
}

TEST(NoGroundTruth, NothingThatNeedsTruthIsComputedAndTheEventsAreCounted) {
  EvalInput in;
  const std::vector<PoseSample> truth = circle_gt(20.0, 10.0);
  const GroundTruth gt(truth);
  in.estimate = truth;  // a real robot's run: estimate and map, no GROUND_TRUTH
  in.map = exact_chain_map(gt, Pose2{}, 20, kSecond / 2);
  const int64_t t0 = truth.front().utime;
  for (int i = 0; i < 20; ++i) in.events.push_back({t0 + i * kSecond / 2, i, EventType::kNewExperience, i - 1, i});
  in.events.push_back({t0 + 12 * kSecond, 40, EventType::kRelocalise, 19, 2});
  in.events.push_back({t0 + 13 * kSecond, 41, EventType::kRelocalise, 2, 2});  // to the current one: not counted
  const EvalResult r = evaluate(in, EvalParams{});
  EXPECT_FALSE(r.ground_truth);
  EXPECT_FALSE(r.alignment.valid);
  EXPECT_FALSE(r.lem.has_value());
  EXPECT_FALSE(r.enm.enm.has_value());
  EXPECT_FALSE(r.exm.arcr.has_value());
  EXPECT_FALSE(r.exm.valid_fraction.has_value());
  EXPECT_FALSE(r.exm.arr.has_value()) << "no base set without truth or --base-duration";
  EXPECT_EQ(r.exm.experiences_created, 20u);
  EXPECT_EQ(r.exm.relocalisations_total, 1u);
  EXPECT_EQ(r.exm.relocalise_to_current, 1u);
  EXPECT_EQ(r.exm.correct_total, 0u);
  // A base set of 5 s from the first pose: experiences 0..10; after it 9 new + 1 re-localisation.
  EvalParams p;
  p.base_duration_s = 5.0;
  const EvalResult b = evaluate(in, p);
  EXPECT_EQ(b.exm.base_set_size, 11u) << "created at or before t0 + 5 s: 0..10";
  ASSERT_TRUE(b.exm.arr.has_value());
  EXPECT_NEAR(*b.exm.arr, 1.0 / 10.0, 1e-12);  // after: experiences 11..19 (9) + 1 re-localisation
}

TEST(Lem, ConstantOffsetEstimateAlignedByFirstExperienceGivesZero) {
  const Pose2 T_world_map{2.0, -1.0, 2.7};
  EvalInput in;
  in.ground_truth = circle_gt(20.0, 10.0);
  const GroundTruth gt(in.ground_truth);
  in.estimate = exact_estimate(in.ground_truth, T_world_map);
  in.map = exact_chain_map(gt, T_world_map, 20, kSecond / 2);
  const EvalResult r = evaluate(in, EvalParams{});
  ASSERT_TRUE(r.alignment.valid);
  EXPECT_NEAR(r.alignment.T_world_map.x, 2.0, 1e-9);
  EXPECT_NEAR(r.alignment.T_world_map.y, -1.0, 1e-9);
  EXPECT_NEAR(r.alignment.T_world_map.theta, 2.7, 1e-9);
  EXPECT_NEAR(r.lem->position_m.rmse, 0.0, 1e-9);
  EXPECT_NEAR(r.lem->orientation_rad.rmse, 0.0, 1e-9);
  ASSERT_TRUE(r.ate.alignment.valid);
  EXPECT_NEAR(r.ate.position_m->rmse, 0.0, 1e-9);
  EXPECT_NEAR(*r.enm.enm, 0.0, 1e-18);
}

TEST(Lem, WithoutAlignmentAnOffsetEstimateShowsTheOffset) {
  // The same offset estimate, evaluated with identity alignment, must not look perfect.
  const GroundTruth gt(circle_gt(10.0, 10.0));
  const LemResult lem = compute_lem(exact_estimate(gt.samples(), Pose2{0.3, 0.4, 0.0}), gt, Pose2{});
  EXPECT_NEAR(lem.position_m.rmse, 0.5, 1e-12);
  EXPECT_NEAR(lem.position_m.std_abs, 0.0, 1e-9);
}

TEST(Lem, AlignmentUsesTheEarliestCreatedExperienceNotTheFirstListed) {
  const GroundTruth gt({{0, {0.0, 0.0, 0.0}}, {10, {1.0, 0.0, 0.0}}});
  ExperienceMap map;
  map.experiences.push_back({0, {5.0, 5.0, 0.0}, 10, false});  // id 0 but created later
  map.experiences.push_back({7, {3.0, 0.0, 0.0}, 0, false});
  const Alignment a = align_by_first_experience(map, gt);
  ASSERT_TRUE(a.valid);
  EXPECT_NEAR(a.T_world_map.x, -3.0, 1e-12);
  EXPECT_NEAR(a.T_world_map.y, 0.0, 1e-12);
}

// metrics.md: the paper's LEM does not fit. An estimate exact everywhere but whose first experience
// sits 0.2 m off looks 0.2 m off throughout under the paper's alignment; ATE's best fit sees an
// exact trajectory.
TEST(Lem, ThePapersLemUsesTheFirstExperienceNotTheBestFit) {
  EvalInput in;
  in.ground_truth = circle_gt(20.0, 10.0);
  const GroundTruth gt(in.ground_truth);
  in.estimate = in.ground_truth;
  in.map = exact_chain_map(gt, Pose2{}, 20, kSecond / 2);
  in.map.experiences[0].pose.x += 0.2;
  const EvalResult r = evaluate(in, EvalParams{});
  ASSERT_TRUE(r.lem.has_value() && r.ate.position_m.has_value());
  EXPECT_NEAR(r.lem->position_m.rmse, 0.2, 1e-9);
  EXPECT_NEAR(r.lem->orientation_rad.rmse, 0.0, 1e-9);
  EXPECT_NEAR(r.ate.position_m->rmse, 0.0, 1e-6);
}

// ---- ATE ----

// A trajectory rotated and shifted as a whole is aligned away: ATE is its shape error only, and the
// transform found is the one applied (Horn / Umeyama: no scale).
TEST(Ate, ARigidlyMovedTrajectoryIsExactAfterTheBestFitAndTheFitIsTheTransform) {
  const GroundTruth gt(circle_gt(20.0, 10.0));
  const Pose2 T_world_map{1.5, -0.7, 2.2};
  const AteResult a = compute_ate(exact_estimate(gt.samples(), T_world_map), {}, gt);
  ASSERT_TRUE(a.alignment.valid);
  EXPECT_NEAR(a.alignment.T_world_map.x, 1.5, 1e-9);
  EXPECT_NEAR(a.alignment.T_world_map.y, -0.7, 1e-9);
  EXPECT_NEAR(a.alignment.T_world_map.theta, 2.2, 1e-9);
  ASSERT_TRUE(a.position_m.has_value());
  EXPECT_NEAR(a.position_m->rmse, 0.0, 1e-9);
  EXPECT_NEAR(a.position_m->max, 0.0, 1e-9);
  EXPECT_EQ(a.samples_used, gt.samples().size());
}

// Known errors after the fit: a square's corners, each pair of opposite corners pushed out from the
// centre by its own factor (1.1 and 1.3). The centroid stays and every corner stays on its ray, so
// the best fit is the identity and the errors are 0.1·√2 twice and 0.3·√2 twice.
TEST(Ate, ReportsRmseMeanMedianAndMaxOfTheErrorsAfterTheFit) {
  const GroundTruth gt({{0, {1.0, 1.0, 0.0}}, {10, {-1.0, 1.0, 0.0}}, {20, {-1.0, -1.0, 0.0}}, {30, {1.0, -1.0, 0.0}}});
  const std::vector<PoseSample> est = {
      {0, {1.1, 1.1, 0.0}}, {10, {-1.3, 1.3, 0.0}}, {20, {-1.1, -1.1, 0.0}}, {30, {1.3, -1.3, 0.0}}};
  const AteResult a = compute_ate(est, {}, gt);
  ASSERT_TRUE(a.position_m.has_value());
  EXPECT_NEAR(a.alignment.T_world_map.x, 0.0, 1e-12);
  EXPECT_NEAR(a.alignment.T_world_map.y, 0.0, 1e-12);
  EXPECT_NEAR(a.alignment.T_world_map.theta, 0.0, 1e-12);
  const double r2 = std::sqrt(2.0);
  EXPECT_NEAR(a.position_m->rmse, std::sqrt(0.1), 1e-12);  // (0.02 + 0.02 + 0.18 + 0.18) / 4
  EXPECT_NEAR(a.position_m->mean, 0.2 * r2, 1e-12);
  EXPECT_NEAR(a.position_m->median, 0.2 * r2, 1e-12);
  EXPECT_NEAR(a.position_m->max, 0.3 * r2, 1e-12);
}

// A translation error only (every estimate d to the east): the fit removes it entirely.
TEST(Ate, AConstantOffsetIsNoError) {
  const GroundTruth gt(circle_gt(10.0, 10.0));
  std::vector<PoseSample> est = gt.samples();
  for (PoseSample& s : est) s.pose.x += 0.3;
  const AteResult a = compute_ate(est, {}, gt);
  ASSERT_TRUE(a.position_m.has_value());
  EXPECT_NEAR(a.position_m->rmse, 0.0, 1e-9);
  EXPECT_NEAR(a.alignment.T_world_map.x, -0.3, 1e-9);
}

// metrics.md: a pose reported while LOCALISING claims nothing. A wild pose then neither counts nor
// moves the fit; it is counted apart. A sample outside the ground truth is counted apart too.
TEST(Ate, PosesReportedWhileLocalisingAreExcludedAndCounted) {
  const GroundTruth gt(circle_gt(10.0, 10.0));
  std::vector<PoseSample> est = gt.samples();
  std::vector<StateSample> states;
  for (const PoseSample& s : est) states.push_back({s.utime, false});
  for (std::size_t i = 100; i < 110; ++i) {
    est[i].pose.x += 5.0;  // where a localising slamd may put its pose
    states[i].localising = true;
  }
  est.push_back({gt.end_utime() + 1000, {0.0, 0.0, 0.0}});
  states.push_back({gt.end_utime() + 1000, false});
  const AteResult a = compute_ate(est, states, gt);
  EXPECT_EQ(a.samples_localising, 10u);
  EXPECT_EQ(a.samples_outside_gt, 1u);
  EXPECT_EQ(a.samples_used, gt.samples().size() - 10);
  ASSERT_TRUE(a.position_m.has_value());
  EXPECT_NEAR(a.position_m->rmse, 0.0, 1e-9);
  // The same samples claimed: they count, and they are 5 m off.
  const AteResult all = compute_ate(est, {}, gt);
  EXPECT_EQ(all.samples_localising, 0u);
  EXPECT_GT(all.position_m->max, 4.0);
  EXPECT_THROW(compute_ate(est, std::vector<StateSample>(3), gt), std::invalid_argument);
}

TEST(Ate, FewerThanTwoSamplesOrNoSpreadHasNoAlignmentAndNoFigure) {
  const GroundTruth gt(circle_gt(10.0, 10.0));
  const AteResult one = compute_ate({gt.samples()[5]}, {}, gt);
  EXPECT_FALSE(one.alignment.valid);
  EXPECT_FALSE(one.position_m.has_value());
  EXPECT_FALSE(one.alignment.reason.empty());
  const AteResult none = compute_ate({}, {}, gt);
  EXPECT_FALSE(none.position_m.has_value());
}

// Windows of laps: a map whose shape is right in the first laps and wrong later shows it per window.
// Just under 8 laps of 10 s, windows of 4: the second window's poses are scaled by 1.1 about the
// centre (a shape error no rigid fit removes), the first's exact.
TEST(Ate, PerWindowOfLapsTheRunsAndTheWindowsOwnFit) {
  const GroundTruth gt(circle_gt(79.9, 10.0));
  std::vector<PoseSample> est = gt.samples();
  for (PoseSample& s : est) {
    if (s.utime > 40 * kSecond) {
      s.pose.x *= 1.1;
      s.pose.y *= 1.1;
    }
  }
  const AteResult a = compute_ate(est, {}, gt, 4.0);
  ASSERT_TRUE(a.lap_length_m.has_value());
  EXPECT_NEAR(*a.lap_length_m, kTwoPi, 1e-3);
  ASSERT_EQ(a.windows.size(), 2u);
  EXPECT_NEAR(a.windows[0].from_lap, 0.0, 1e-9);
  EXPECT_NEAR(a.windows[0].to_lap, 4.0, 0.01);
  EXPECT_NEAR(a.windows[1].from_lap, 4.0, 0.01);
  EXPECT_NEAR(a.windows[1].to_lap, 7.99, 0.01);
  EXPECT_EQ(a.windows[0].samples + a.windows[1].samples, a.samples_used);
  // The window's own fit cannot remove a scale error: 0.1 m on every pose of the second window.
  ASSERT_TRUE(a.windows[1].rmse_own_fit.has_value());
  EXPECT_NEAR(*a.windows[1].rmse_own_fit, 0.1, 0.002);
  EXPECT_NEAR(*a.windows[0].rmse_own_fit, 0.0, 1e-6);
  EXPECT_GT(a.windows[1].rmse, a.windows[0].rmse);
  // No lap length (a straight line), no windows; the run's figure stays.
  const GroundTruth line({{0, {0.0, 0.0, 0.0}}, {kSecond, {1.0, 0.0, 0.0}}, {2 * kSecond, {2.0, 0.0, 0.0}}});
  const AteResult s = compute_ate(line.samples(), {}, line);
  EXPECT_TRUE(s.windows.empty());
  EXPECT_TRUE(s.position_m.has_value());
}

// evaluate() reports ATE over VITA_POSE with the states it read, and nothing without ground truth.
TEST(Ate, EvaluateExcludesTheLocalisingPosesOfTheRun) {
  EvalInput in;
  in.ground_truth = circle_gt(20.0, 10.0);
  const GroundTruth gt(in.ground_truth);
  in.estimate = in.ground_truth;
  for (const PoseSample& s : in.estimate) in.states.push_back({s.utime, s.utime < 2 * kSecond});
  in.map = exact_chain_map(gt, Pose2{}, 20, kSecond / 2);
  const EvalResult r = evaluate(in, EvalParams{});
  EXPECT_EQ(r.ate.samples_localising, 100u);  // 50 Hz for 2 s
  EvalInput blind = in;
  blind.ground_truth.clear();
  EXPECT_FALSE(evaluate(blind, EvalParams{}).ate.position_m.has_value());
}

TEST(Lem, ReportsRmseMeanAndStdOfKnownErrorsIncludingAcrossTheWrap) {
  const GroundTruth gt({{0, {0.0, 0.0, -kPi + 0.05}}, {100, {0.0, 0.0, -kPi + 0.05}}});
  const std::vector<PoseSample> est = {{0, {0.1, 0.0, kPi - 0.05}},    // |e| = 0.1 m, 0.1 rad
                                       {100, {0.0, 0.3, -kPi + 0.35}},  // |e| = 0.3 m, 0.3 rad
                                       {101, {9.0, 9.0, 0.0}}};         // no ground truth: excluded
  const LemResult lem = compute_lem(est, gt, Pose2{});
  EXPECT_EQ(lem.samples_used, 2u);
  EXPECT_EQ(lem.samples_outside_gt, 1u);
  EXPECT_NEAR(lem.position_m.rmse, std::sqrt(0.05), 1e-12);
  EXPECT_NEAR(lem.position_m.mean_abs, 0.2, 1e-12);
  EXPECT_NEAR(lem.position_m.std_abs, 0.1, 1e-9);
  EXPECT_NEAR(lem.orientation_rad.rmse, std::sqrt(0.05), 1e-9);
  EXPECT_NEAR(lem.orientation_rad.mean_abs, 0.2, 1e-9);
}

TEST(Lem, NoAlignmentWithoutExperiencesOrGroundTruthAtTheFirst) {
  const GroundTruth gt({{100, {0.0, 0.0, 0.0}}, {200, {1.0, 0.0, 0.0}}});
  ExperienceMap map;
  EXPECT_FALSE(align_by_first_experience(map, gt).valid);
  map.experiences.push_back({0, {0.0, 0.0, 0.0}, 50, false});
  const Alignment a = align_by_first_experience(map, gt);
  EXPECT_FALSE(a.valid);
  EXPECT_NE(a.reason.find("no ground truth"), std::string::npos);
}

TEST(Enm, KnownHeadingErrorGivesKnownEnm) {
  const GroundTruth gt(circle_gt(10.0, 10.0));
  const Pose2 T_world_map{0.4, 0.1, -1.0};
  ExperienceMap map = exact_chain_map(gt, T_world_map, 3, kSecond);
  map.experiences[2].pose.theta = wrap_angle(map.experiences[2].pose.theta + 0.1);
  const EnmResult r = compute_enm(map, gt);
  EXPECT_EQ(r.links_used, 2u);
  // Link 0->1 is exact; link 1->2 is off by 0.1 rad and nothing in translation.
  EXPECT_NEAR(*r.enm, 0.01 / 2, 1e-12);
  EXPECT_NEAR(*r.rotation, 0.01 / 2, 1e-12);
  EXPECT_NEAR(*r.translation, 0.0, 1e-20);
}

TEST(Enm, MatchesTheHandWorkedExampleOfTheDocs) {
  // docs/evaluation.md: x1 = (1,0,0), x2 = (0,1,pi/2); map x1 = (0,0,0), x2 = (-1,1,pi/2+0.1).
  const GroundTruth gt({{0, {1.0, 0.0, 0.0}}, {10, {0.0, 1.0, kPi / 2}}});
  ExperienceMap map;
  map.experiences.push_back({1, {0.0, 0.0, 0.0}, 0, false});
  map.experiences.push_back({2, {-1.0, 1.0, kPi / 2 + 0.1}, 10, false});
  map.links.push_back({1, 2, false, {}});
  const EnmResult r = compute_enm(map, gt);
  EXPECT_NEAR(*r.translation, 0.0, 1e-24);
  EXPECT_NEAR(*r.rotation, 0.01, 1e-12);
}

TEST(Enm, KnownTranslationErrorGivesKnownEnm) {
  const GroundTruth gt(circle_gt(10.0, 10.0));
  ExperienceMap map = exact_chain_map(gt, Pose2{}, 3, kSecond);
  map.experiences[2].pose.x += 0.3;
  map.experiences[2].pose.y += 0.4;
  const EnmResult r = compute_enm(map, gt);
  EXPECT_NEAR(*r.translation, 0.25 / 2, 1e-12);
  EXPECT_NEAR(*r.rotation, 0.0, 1e-20);
  EXPECT_NEAR(*r.enm, 0.125, 1e-12);
}

TEST(Enm, HeadingsAcrossThePiWrapGiveTheirSmallError) {
  // The second experience faces 3.13 rad from the first; the map has it 0.02 rad further on, past
  // pi (stored as -3.133). The error is 0.02 rad, not 2 pi - 0.02.
  const GroundTruth gt({{0, {1.0, 0.0, 0.0}}, {10, {1.0, 0.0, 3.13}}});
  ExperienceMap map;
  map.experiences.push_back({1, {1.0, 0.0, 0.0}, 0, false});
  map.experiences.push_back({2, {1.0, 0.0, wrap_angle(3.15)}, 10, false});
  map.links.push_back({1, 2, false, {}});
  const EnmResult r = compute_enm(map, gt);
  EXPECT_NEAR(*r.rotation, 0.0004, 1e-12);
  EXPECT_NEAR(*r.translation, 0.0, 1e-20);
}

TEST(Enm, ExcludesAndCountsLinksItCannotEvaluate) {
  const GroundTruth gt(circle_gt(10.0, 10.0));
  ExperienceMap map = exact_chain_map(gt, Pose2{}, 3, kSecond);
  map.links.push_back({2, 42, false, {}});                               // no such experience
  map.experiences.push_back({3, Pose2{}, 60 * kSecond, false});  // created after ground truth ends
  map.links.push_back({2, 3, false, {}});
  const EnmResult r = compute_enm(map, gt);
  EXPECT_EQ(r.links_used, 2u);
  EXPECT_EQ(r.links_excluded, 2u);
  ExperienceMap empty;
  EXPECT_FALSE(compute_enm(empty, gt).enm.has_value());
}

TEST(BaseSet, EndsAfterOneFullRevolutionAroundTheCentre) {
  EvalParams params;
  // Starting at an arbitrary phase, counter-clockwise; 10 s per revolution.
  const GroundTruth ccw(circle_gt(25.0, 10.0, 0.3));
  const auto end = base_set_end(ccw, params);
  ASSERT_TRUE(end.has_value());
  EXPECT_NEAR(static_cast<double>(*end), 10.0 * kSecond, 2.0);
  // Clockwise counts the same.
  const GroundTruth cw(circle_gt(25.0, 10.0, 1.0, -1.0));
  EXPECT_NEAR(static_cast<double>(*base_set_end(cw, params)), 10.0 * kSecond, 2.0);
}

TEST(BaseSet, CountsNetTravelAroundTheCentreNotBackAndForth) {
  // Half a turn forwards (0-5 s), back again (5-10 s), then a whole turn (10-20 s): the revolution
  // is complete at 20 s; summing |dphi| would end it at 10 s.
  std::vector<PoseSample> samples;
  for (int64_t u = 0; u <= 25 * kSecond; u += 20'000) {
    const double t = static_cast<double>(u) / kSecond;
    const double phi = t <= 5 ? kPi * t / 5 : t <= 10 ? kPi * (10 - t) / 5 : kTwoPi * (t - 10) / 10;
    samples.push_back({u, {std::cos(phi), std::sin(phi), wrap_angle(phi)}});
  }
  const auto end = base_set_end(GroundTruth(samples), EvalParams{});
  ASSERT_TRUE(end.has_value());
  EXPECT_NEAR(static_cast<double>(*end), 20.0 * kSecond, 2.0);
}

TEST(BaseSet, UsesTheConfiguredCentreAndDuration) {
  EvalParams params;
  const GroundTruth gt(circle_gt(25.0, 10.0, 0.0, 1.0, 3.0, 3.0));  // around (3, 3)
  EXPECT_FALSE(base_set_end(gt, params).has_value());  // never goes around (0, 0)
  params.centre_x = 3.0;
  params.centre_y = 3.0;
  EXPECT_NEAR(static_cast<double>(*base_set_end(gt, params)), 10.0 * kSecond, 2.0);
  params.base_duration_s = 4.5;
  EXPECT_EQ(*base_set_end(gt, params), 4'500'000);
}

// A scripted run along a line: ground truth at every whole second, events at whole seconds.
class ScriptedExm : public ::testing::Test {
 protected:
  void at(int64_t t_s, Pose2 pose) { gt_samples_.push_back({t_s * kSecond, pose}); }
  void ev(int64_t t_s, EventType type, int32_t from, int32_t to) {
    events_.push_back({t_s * kSecond, t_s, type, from, to});
    if (type == EventType::kNewExperience) map_.experiences.push_back({to, Pose2{}, t_s * kSecond, false});
  }
  ExmResult run(double base_duration_s) {
    EvalParams params;
    params.base_duration_s = base_duration_s;
    return compute_exm(events_, map_, GroundTruth(gt_samples_), params);
  }
  std::vector<PoseSample> gt_samples_;
  std::vector<ExperienceEvent> events_;
  ExperienceMap map_;
};

TEST_F(ScriptedExm, CountsReLocalisationsCorrectnessAtTheThresholdsAndValidity) {
  using E = EventType;
  for (int t = 0; t <= 13; ++t) at(t, {10.0 * t, 0.0, 0.0});  // far apart by default
  gt_samples_[0].pose = {0.0, 0.0, 0.0};
  gt_samples_[1].pose = {1.0, 0.0, 0.0};
  gt_samples_[4].pose = {0.0799, 0.0, 0.0};                // 0.0799 m from exp 0: correct
  gt_samples_[6].pose = {1.0801, 0.0, 0.0};                // 0.0801 m from exp 1: incorrect
  gt_samples_[9].pose = {0.0, 0.0, deg_to_rad(4.5)};       // 4.5 deg from exp 0: correct
  gt_samples_[11].pose = {1.0, 0.0, -deg_to_rad(4.7)};     // 4.7 deg from exp 1: incorrect
  ev(0, E::kNewExperience, -1, 0);
  ev(1, E::kNewExperience, 0, 1);
  ev(2, E::kNewExperience, 1, 2);
  // ---- base set ends at 2.5 s
  ev(3, E::kSameExperience, 2, 2);
  ev(4, E::kRelocalise, 2, 0);
  ev(5, E::kNewExperience, 0, 3);   // valid
  ev(6, E::kRelocalise, 3, 1);
  ev(7, E::kNewExperience, 1, 4);   // invalid
  ev(8, E::kNewExperience, 4, 5);   // invalid
  ev(9, E::kRelocalise, 5, 0);
  ev(10, E::kNewExperience, 0, 6);  // valid again
  ev(11, E::kRelocalise, 6, 1);
  ev(12, E::kRelocalise, 1, 1);     // not a change of experience
  ev(13, E::kRelocalise, 1, 99);    // target never created
  const ExmResult r = run(2.5);

  EXPECT_EQ(r.base_set_size, 3u);
  EXPECT_EQ(r.experience_events_after_base, 8u);  // 4 new + 4 re-localisations
  EXPECT_EQ(r.relocalisations_after_base, 4u);
  EXPECT_EQ(r.correct_after_base, 2u);
  ASSERT_TRUE(r.arr && r.arcr);
  EXPECT_DOUBLE_EQ(*r.arr, 0.5);
  EXPECT_DOUBLE_EQ(*r.arcr, 0.5);
  EXPECT_DOUBLE_EQ(*r.arcr_after_base, 0.5);  // nothing re-localised inside the base set
  ASSERT_EQ(r.relocalisations.size(), 4u);
  EXPECT_TRUE(r.relocalisations[0].correct);
  EXPECT_FALSE(r.relocalisations[1].correct);
  EXPECT_TRUE(r.relocalisations[2].correct);
  EXPECT_FALSE(r.relocalisations[3].correct);
  EXPECT_NEAR(r.relocalisations[3].angle_error_rad, deg_to_rad(4.7), 1e-12);
  EXPECT_EQ(r.experiences_created, 7u);
  EXPECT_EQ(r.valid_experiences, 5u);
  EXPECT_DOUBLE_EQ(*r.valid_fraction, 5.0 / 7.0);
  EXPECT_EQ(r.relocalise_to_current, 1u);
  EXPECT_EQ(r.relocalise_unknown_target, 1u);
}

TEST(Closure, DefaultsAreThePapersThresholdsAndTheFalseClosureTolerance) {
  const EvalParams p;
  EXPECT_DOUBLE_EQ(p.correct_position_m, 0.08);
  EXPECT_DOUBLE_EQ(rad_to_deg(p.correct_angle_rad), 4.6);
  EXPECT_DOUBLE_EQ(p.false_closure_position_m, 0.25);
  EXPECT_DOUBLE_EQ(rad_to_deg(p.false_closure_angle_rad), 15.0);
}

TEST(Closure, ThePaperThresholdsMakeCorrectAndTheToleranceSplitsTheWrongOnes) {
  const EvalParams p;
  EXPECT_EQ(classify_closure(0.08, deg_to_rad(4.6), p), Closure::kCorrect);  // bounds inclusive
  EXPECT_EQ(classify_closure(0.0801, 0.0, p), Closure::kNeighbourMiss);
  EXPECT_EQ(classify_closure(0.0, deg_to_rad(4.7), p), Closure::kNeighbourMiss);
  EXPECT_EQ(classify_closure(0.25, deg_to_rad(15.0), p), Closure::kNeighbourMiss);
  EXPECT_EQ(classify_closure(0.2501, 0.0, p), Closure::kFalse);
  EXPECT_EQ(classify_closure(0.0, deg_to_rad(15.1), p), Closure::kFalse);  // heading alone suffices
  EXPECT_EQ(classify_closure(3.0, kPi, p), Closure::kFalse);
  EvalParams wide = p;
  wide.false_closure_position_m = 0.5;
  EXPECT_EQ(classify_closure(0.4, 0.0, wide), Closure::kNeighbourMiss);
  EXPECT_STREQ(closure_name(Closure::kCorrect), "correct");
  EXPECT_STREQ(closure_name(Closure::kNeighbourMiss), "neighbour");
  EXPECT_STREQ(closure_name(Closure::kFalse), "false");
}

TEST_F(ScriptedExm, CountsFalseClosuresApartFromNeighbourMisses) {
  using E = EventType;
  for (int t = 0; t <= 8; ++t) at(t, {10.0 * t, 0.0, 0.0});  // far apart by default
  gt_samples_[0].pose = {0.0, 0.0, 0.0};
  gt_samples_[1].pose = {1.0, 0.0, 0.0};
  gt_samples_[2].pose = {2.0, 0.0, 0.0};
  gt_samples_[4].pose = {0.03, 0.0, 0.0};               // 3 cm from exp 0: correct
  gt_samples_[5].pose = {1.1, 0.0, 0.0};                // 0.1 m from exp 1: a neighbour miss
  gt_samples_[6].pose = {0.5, 0.0, 0.0};                // 1.5 m from exp 2: false
  gt_samples_[7].pose = {0.0, 0.0, deg_to_rad(20.0)};   // on exp 0, 20 deg off: false
  ev(0, E::kNewExperience, -1, 0);
  ev(1, E::kNewExperience, 0, 1);
  ev(2, E::kNewExperience, 1, 2);
  ev(4, E::kRelocalise, 2, 0);
  ev(5, E::kRelocalise, 0, 1);
  ev(6, E::kRelocalise, 1, 2);
  ev(7, E::kRelocalise, 2, 0);
  const ExmResult r = run(2.5);

  ASSERT_EQ(r.relocalisations.size(), 4u);
  EXPECT_EQ(r.relocalisations[0].closure, Closure::kCorrect);
  EXPECT_EQ(r.relocalisations[1].closure, Closure::kNeighbourMiss);
  EXPECT_EQ(r.relocalisations[2].closure, Closure::kFalse);
  EXPECT_EQ(r.relocalisations[3].closure, Closure::kFalse);
  EXPECT_EQ(r.correct_total, 1u);
  EXPECT_DOUBLE_EQ(*r.arcr, 0.25);  // ARCR stays the paper's
  EXPECT_EQ(r.neighbour_misses, 1u);
  EXPECT_EQ(r.false_closures, 2u);
  ASSERT_TRUE(r.false_closure_worst_m.has_value());
  EXPECT_NEAR(*r.false_closure_worst_m, 1.5, 1e-12);
  ASSERT_TRUE(r.neighbour_miss_share.has_value());
  EXPECT_DOUBLE_EQ(*r.neighbour_miss_share, 1.0 / 3.0);
  // A neighbour miss is still paper-wrong: the experiences after it are invalid as before.
  EXPECT_FALSE(r.relocalisations[1].correct);

  // The trace carries each verdict.
  EvalInput input;
  input.ground_truth = gt_samples_;
  input.events = events_;
  input.map = map_;
  const std::vector<CycleTrace> trace = trace_cycles(input, r);
  ASSERT_EQ(trace.size(), 7u);
  EXPECT_FALSE(trace[2].relocalisation.has_value());
  EXPECT_EQ(trace[3].relocalisation->closure, Closure::kCorrect);
  EXPECT_EQ(trace[4].relocalisation->closure, Closure::kNeighbourMiss);
  EXPECT_EQ(trace[5].relocalisation->closure, Closure::kFalse);
  EXPECT_EQ(trace[6].relocalisation->closure, Closure::kFalse);
}

TEST_F(ScriptedExm, NoWrongReLocalisationLeavesTheShareAndTheWorstUndefined) {
  using E = EventType;
  for (int t = 0; t <= 4; ++t) at(t, {0.01 * t, 0.0, 0.0});
  ev(0, E::kNewExperience, -1, 0);
  ev(1, E::kNewExperience, 0, 1);
  ev(3, E::kRelocalise, 1, 0);  // 3 cm: correct
  const ExmResult r = run(1.5);
  EXPECT_EQ(r.false_closures, 0u);
  EXPECT_EQ(r.neighbour_misses, 0u);
  EXPECT_FALSE(r.false_closure_worst_m.has_value());
  EXPECT_FALSE(r.neighbour_miss_share.has_value());
}

TEST_F(ScriptedExm, AWiderToleranceTurnsAFalseClosureIntoANeighbourMiss) {
  using E = EventType;
  for (int t = 0; t <= 3; ++t) at(t, {0.4 * t, 0.0, 0.0});
  ev(0, E::kNewExperience, -1, 0);
  ev(1, E::kNewExperience, 0, 1);
  ev(2, E::kRelocalise, 1, 0);  // 0.8 m from where experience 0 was made
  EvalParams params;
  params.base_duration_s = 1.5;
  EXPECT_EQ(compute_exm(events_, map_, GroundTruth(gt_samples_), params).false_closures, 1u);
  params.false_closure_position_m = 1.0;
  const ExmResult r = compute_exm(events_, map_, GroundTruth(gt_samples_), params);
  EXPECT_EQ(r.false_closures, 0u);
  EXPECT_EQ(r.neighbour_misses, 1u);
}

TEST_F(ScriptedExm, ExperienceSpacingIsTheMedianStepToEachNewExperience) {
  using E = EventType;
  // Steps of 0.1 m and 2 deg, one of 0.3 m and 10 deg; and a re-localisation back to experience 0
  // before experience 5, which is then 0.12 m and 1 deg from it (not from experience 4).
  const double xs[] = {0.0, 0.1, 0.2, 0.5, 0.6, 0.0, 0.12};
  const double degs[] = {0.0, 2.0, 4.0, 14.0, 16.0, 0.0, 1.0};
  for (int t = 0; t <= 6; ++t) at(t, {xs[t], 0.0, deg_to_rad(degs[t])});
  for (int t = 0; t <= 4; ++t) ev(t, E::kNewExperience, t - 1, t);
  ev(5, E::kRelocalise, 4, 0);
  ev(6, E::kNewExperience, 0, 5);
  const ExmResult r = run(10.0);
  EXPECT_EQ(r.spacing_steps, 5u);  // 0->1, 1->2, 2->3, 3->4, 0->5
  ASSERT_TRUE(r.spacing_median_m && r.spacing_median_heading_rad);
  EXPECT_NEAR(*r.spacing_median_m, 0.1, 1e-12);               // 0.1 0.1 0.1 0.12 0.3
  EXPECT_NEAR(*r.spacing_median_heading_rad, deg_to_rad(2.0), 1e-12);  // 1 2 2 2 10
}

TEST_F(ScriptedExm, ArcrIsUndefinedWithoutReLocalisationsNotOne) {
  using E = EventType;
  for (int t = 0; t <= 5; ++t) at(t, {static_cast<double>(t), 0.0, 0.0});
  for (int t = 0; t <= 5; ++t) ev(t, E::kNewExperience, t - 1, t);
  const ExmResult r = run(1.5);
  EXPECT_EQ(r.experience_events_after_base, 4u);
  ASSERT_TRUE(r.arr.has_value());
  EXPECT_DOUBLE_EQ(*r.arr, 0.0);
  EXPECT_FALSE(r.arcr.has_value());
  EXPECT_DOUBLE_EQ(*r.valid_fraction, 1.0);
}

TEST_F(ScriptedExm, ArrIsUndefinedWhenNothingHappensAfterTheBaseSet) {
  for (int t = 0; t <= 5; ++t) at(t, {static_cast<double>(t), 0.0, 0.0});
  ev(0, EventType::kNewExperience, -1, 0);
  const ExmResult r = run(3.0);
  EXPECT_FALSE(r.arr.has_value());
  EXPECT_FALSE(r.arcr.has_value());
}

TEST_F(ScriptedExm, AnIncorrectReLocalisationDuringTheBaseSetInvalidatesLaterExperiencesAndCountsInArcr) {
  using E = EventType;
  for (int t = 0; t <= 5; ++t) at(t, {static_cast<double>(t), 0.0, 0.0});
  ev(0, E::kNewExperience, -1, 0);
  ev(1, E::kNewExperience, 0, 1);
  ev(2, E::kRelocalise, 1, 0);  // 2 m away: incorrect, inside the base set
  ev(4, E::kNewExperience, 0, 2);
  const ExmResult r = run(3.0);
  EXPECT_EQ(r.relocalisations_total, 1u);
  EXPECT_EQ(r.relocalisations_after_base, 0u);
  EXPECT_FALSE(r.relocalisations[0].after_base_set);
  // metrics.md: ARCR = correct / re-localisations, all of them: the false loop closure of the first
  // lap counts (the paper's single-sense runs fail there).
  ASSERT_TRUE(r.arcr.has_value());
  EXPECT_DOUBLE_EQ(*r.arcr, 0.0);
  EXPECT_FALSE(r.arcr_after_base.has_value());
  EXPECT_DOUBLE_EQ(*r.arr, 0.0);
  EXPECT_EQ(r.valid_experiences, 2u);
  EXPECT_EQ(r.experiences_created, 3u);
}

TEST_F(ScriptedExm, TakesCreationTimesFromEventsWhenTheMapLacksTheExperience) {
  using E = EventType;
  for (int t = 0; t <= 5; ++t) at(t, {0.0, 0.0, 0.0});
  ev(0, E::kNewExperience, -1, 0);
  ev(1, E::kNewExperience, 0, 1);
  map_.experiences.clear();
  ev(4, E::kRelocalise, 1, 0);
  const ExmResult r = run(2.0);
  ASSERT_EQ(r.relocalisations.size(), 1u);
  EXPECT_TRUE(r.relocalisations[0].correct);
  EXPECT_DOUBLE_EQ(*r.arcr, 1.0);
}

TEST_F(ScriptedExm, ExcludesEventsOutsideTheGroundTruthAndCountsThem) {
  using E = EventType;
  for (int t = 0; t <= 3; ++t) at(t, {0.0, 0.0, 0.0});
  ev(0, E::kNewExperience, -1, 0);
  ev(2, E::kNewExperience, 0, 1);
  ev(5, E::kRelocalise, 1, 0);  // ground truth ended at 3 s
  const ExmResult r = run(1.0);
  EXPECT_EQ(r.events_outside_gt, 1u);
  EXPECT_EQ(r.relocalisations_total, 0u);
  EXPECT_EQ(r.experience_events_after_base, 1u);
}

TEST_F(ScriptedExm, TheTraceGivesEveryCycleInTimeOrderWithItsReLocalisationAndItsMatch) {
  using E = EventType;
  for (int t = 0; t <= 4; ++t) at(t, {static_cast<double>(t), 0.0, 0.0});
  gt_samples_[3].pose = {0.05, 0.0, 0.0};  // 5 cm from experience 0: correct
  gt_samples_[4].pose = {0.0, 0.0, 0.0};
  ev(0, E::kNewExperience, -1, 0);
  ev(1, E::kNewExperience, 0, 1);
  ev(4, E::kRelocalise, 0, 1);  // 1 m from where experience 1 was made: incorrect
  ev(3, E::kRelocalise, 1, 0);  // listed out of order
  ev(5, E::kSameExperience, 1, 1);  // after the ground truth
  EvalInput input;
  input.ground_truth = gt_samples_;
  input.events = events_;
  input.map = map_;
  TemplateMatch m;
  m.cycle = 3;
  m.template_id = 7;
  m.error = 0.04;
  m.visual_shift = -2;
  m.visual_used = true;
  input.matches.push_back(m);
  const ExmResult exm = run(1.5);
  const std::vector<CycleTrace> trace = trace_cycles(input, exm);

  ASSERT_EQ(trace.size(), 5u);
  for (std::size_t i = 0; i + 1 < trace.size(); ++i) EXPECT_LT(trace[i].event.utime, trace[i + 1].event.utime);
  EXPECT_DOUBLE_EQ(trace[2].t_s, 3.0);
  EXPECT_EQ(trace[2].event.to_id, 0);
  ASSERT_TRUE(trace[2].relocalisation.has_value());
  EXPECT_TRUE(trace[2].relocalisation->correct);
  EXPECT_NEAR(trace[2].relocalisation->position_error_m, 0.05, 1e-12);
  ASSERT_TRUE(trace[2].match.has_value());
  EXPECT_EQ(trace[2].match->template_id, 7);
  EXPECT_EQ(trace[2].match->visual_shift, -2);
  ASSERT_TRUE(trace[3].relocalisation.has_value());
  EXPECT_FALSE(trace[3].relocalisation->correct);
  EXPECT_NEAR(trace[3].relocalisation->position_error_m, 1.0, 1e-12);
  EXPECT_FALSE(trace[3].match.has_value());  // no VITA_MATCH for that cycle
  EXPECT_FALSE(trace[0].relocalisation.has_value());
  ASSERT_TRUE(trace[0].gt.has_value());
  EXPECT_FALSE(trace[4].gt.has_value());  // no ground truth at 5 s
}

TEST_F(ScriptedExm, TheTraceListsTheSimulatedFaultsActiveAtEachCycle) {
  using E = EventType;
  for (int t = 0; t <= 4; ++t) at(t, {static_cast<double>(t), 0.0, 0.0});
  for (int t = 0; t <= 4; ++t) ev(t, E::kNewExperience, t - 1, t);
  EvalInput input;
  input.ground_truth = gt_samples_;
  input.events = events_;
  input.map = map_;
  input.faults = {{0, "dead_whisker 3", true},
                  {1 * kSecond, "board_offline 2", true},
                  {3 * kSecond, "board_offline 2", false},  // ends: not active at 3 s
                  {4 * kSecond, "camera_blackout", true}};
  const std::vector<CycleTrace> trace = trace_cycles(input, run(10.0));
  ASSERT_EQ(trace.size(), 5u);
  EXPECT_EQ(trace[0].active_faults, (std::vector<std::string>{"dead_whisker 3"}));
  EXPECT_EQ(trace[1].active_faults, (std::vector<std::string>{"board_offline 2", "dead_whisker 3"}));
  EXPECT_EQ(trace[2].active_faults, (std::vector<std::string>{"board_offline 2", "dead_whisker 3"}));
  EXPECT_EQ(trace[3].active_faults, (std::vector<std::string>{"dead_whisker 3"}));
  EXPECT_EQ(trace[4].active_faults, (std::vector<std::string>{"camera_blackout", "dead_whisker 3"}));
}

TEST(ExperienceIndex, AnswersAsFindForEveryIdTheFirstOfRepeatedIdsAndNothingForAnUnknownOne) {
  ExperienceMap map;
  for (int32_t id : {4, 7, -1, 7, 0}) map.experiences.push_back({id, {static_cast<double>(map.experiences.size()), 0, 0}, 0, false});
  const ExperienceIndex index(map);
  for (int32_t id : {4, 7, -1, 0, 5, 100}) EXPECT_EQ(index.find(id), map.find(id)) << "id " << id;
  EXPECT_EQ(index.find(7), &map.experiences[1]);
  EXPECT_EQ(index.find(5), nullptr);
}

// ---- Localisation after a kidnap, and in a session on a saved map ----

// A 1 m circle, one lap in 20 s (lap 2π m), facing outwards; kidnapped at 25 s half a lap ahead. In
// the first lap an experience every second: experience i was created where the robot is at i s (and
// again at i + 20 s, and, after the kidnap, at i - 10 s).
class Localising : public ::testing::Test {
 protected:
  static Pose2 truth(double t_s) { return t_s < 25.0 ? circle_pose(t_s, 20.0) : circle_pose(t_s + 10.0, 20.0); }
  void SetUp() override {
    for (int64_t u = 0; u <= 31 * kSecond; u += 20'000) in_.ground_truth.push_back({u, truth(u * 1e-6)});
    in_.kidnaps.push_back({25 * kSecond, truth(25.0)});
    for (int i = 0; i < 20; ++i) {
      in_.map.experiences.push_back({i, Pose2{}, i * kSecond, false});
      ev(i, EventType::kNewExperience, i - 1, i);
    }
    for (int j = 0; j < 5; ++j) ev(20 + j, EventType::kRelocalise, j == 0 ? 19 : j - 1, j);  // the second lap: correct
    // Kidnapped at 25 s: slamd goes on from experience 4 as if nothing happened.
    ev(26, EventType::kSameExperience, 4, 4);
    ev(27, EventType::kNewExperience, 4, 100);
    ev(28, EventType::kNewExperience, 100, 101);
  }
  void ev(double t_s, EventType type, int32_t from, int32_t to, bool localising = false) {
    in_.events.push_back({std::llround(t_s * kSecond), ++cycle_, type, from, to, localising});
  }
  LocalisationReport run(const EvalParams& params = {}) {
    const EvalResult r = evaluate(in_, params);
    EXPECT_TRUE(r.localisation.has_value());
    return r.localisation.value_or(LocalisationReport{});
  }
  EvalInput in_;
  int64_t cycle_ = 0;
};

TEST_F(Localising, AKidnapRecoveredWithoutAFalseLocalisation) {
  ev(29, EventType::kNewExperience, 101, 102);
  ev(30, EventType::kRelocalise, 102, 0);    // at 30 s the robot is where experience 0 was made: correct
  // Staying there while the robot drives on (a saved map learns nothing new): the pose is experience
  // 0 plus the odometry since, right, though the robot is 0.16 m and then 0.28 m from where 0 was made.
  // Judged as claims, they once made the second a false localisation and the recovery "never".
  ev(30.5, EventType::kSameExperience, 0, 0);
  ev(30.9, EventType::kSameExperience, 0, 0);
  ev(30.95, EventType::kRelocalise, 0, 1);  // 0.05 s before where 1 was made: 0.016 m / 0.9 deg
  const LocalisationReport r = run();
  ASSERT_EQ(r.instants.size(), 1u);
  const Localisation& l = r.instants[0];
  EXPECT_EQ(l.instant.kind, LocalisationInstant::Kind::kKidnap);
  EXPECT_EQ(l.instant.utime, 25 * kSecond);
  ASSERT_TRUE(l.localised);
  EXPECT_EQ(l.localised_utime, 30 * kSecond);
  EXPECT_EQ(l.localised_by.to_id, 0);
  EXPECT_NEAR(*l.time_s, 5.0, 1e-9);
  EXPECT_NEAR(*l.distance_m, 5.0 * kTwoPi / 20.0, 1e-3) << "the jump itself is no travel";
  ASSERT_TRUE(r.lap_length_m.has_value());
  EXPECT_NEAR(*r.lap_length_m, kTwoPi, 1e-3) << "path per 2 pi of heading, not across the kidnap";
  EXPECT_NEAR(*l.laps, 0.25, 1e-3);
  EXPECT_EQ(l.false_localisations, 0u) << "staying on experience 4 after the kidnap is no closure";
  const double early = 2.0 * std::sin(kTwoPi / 20.0 * 0.05 / 2.0);
  EXPECT_EQ(l.lem_events, 2u) << "the re-localisations; not the cycles that stay on a place";
  EXPECT_NEAR(*l.lem_after_m, 0.5 * early, 1e-6);
  EXPECT_NEAR(*l.lem_after_angle_rad, 0.5 * kTwoPi / 20.0 * 0.05, 1e-6);
  EXPECT_EQ(r.localised, 1u);
  EXPECT_EQ(r.within_one_lap, 1u);
  EXPECT_NEAR(*r.worst_laps, 0.25, 1e-3);
  EXPECT_EQ(r.false_localisations, 0u);
}

TEST_F(Localising, AFalseLocalisationBeforeTheRecoveryIsCountedOnce) {
  ev(29, EventType::kRelocalise, 101, 5);     // the robot is where 19 was made: 5 is 1.6 m off
  ev(29.5, EventType::kSameExperience, 5, 5);  // still there: the same false claim
  ev(30, EventType::kRelocalise, 5, 0);
  const LocalisationReport r = run();
  const Localisation& l = r.instants.at(0);
  ASSERT_TRUE(l.localised);
  EXPECT_EQ(l.localised_utime, 30 * kSecond);
  EXPECT_EQ(l.false_localisations, 1u);
  ASSERT_EQ(l.false_events.size(), 1u);
  EXPECT_EQ(l.false_events[0].to_id, 5);
  EXPECT_NEAR(l.false_events[0].position_error_m, 2.0 * std::sin(kTwoPi * 6.0 / 20.0 / 2.0), 1e-6);
  EXPECT_EQ(r.with_false_localisation, 1u);
  EXPECT_EQ(r.false_localisations_max, 1u);
}

TEST_F(Localising, ACorrectLocalisationFollowedByAFalseOneIsNotTheRecovery) {
  ev(29, EventType::kRelocalise, 101, 19);   // correct ...
  ev(30, EventType::kRelocalise, 19, 7);     // ... then a false closure: the first did not hold
  const LocalisationReport never = run();
  EXPECT_FALSE(never.instants.at(0).localised);
  EXPECT_FALSE(never.instants.at(0).time_s.has_value());
  EXPECT_EQ(never.instants.at(0).false_localisations, 1u);
  EXPECT_EQ(never.localised, 0u);
  EXPECT_EQ(never.within_two_laps, 0u);
  EXPECT_FALSE(never.worst_laps.has_value()) << "never localised: no worst figure";
  EXPECT_FALSE(never.lem_after_m.has_value());
  ev(31, EventType::kRelocalise, 7, 1);      // at 31 s the robot is where 1 was made
  const Localisation l = run().instants.at(0);
  ASSERT_TRUE(l.localised);
  EXPECT_EQ(l.localised_utime, 31 * kSecond);
  EXPECT_EQ(l.false_localisations, 1u);
}

TEST_F(Localising, ANewExperienceOrAnEventReportingLocalisingIsNoClaim) {
  ev(29, EventType::kSameExperience, 101, 7, true);  // a hypothesis while LOCALISING: no claim
  ev(30, EventType::kNewExperience, 101, 102);
  const Localisation l = run().instants.at(0);
  EXPECT_FALSE(l.localised) << "a new experience is made where the robot is: it recognises nothing";
  EXPECT_EQ(l.false_localisations, 0u);
}

TEST_F(Localising, TimeReportingLocalisingIsCountedFromTheStateSamples) {
  for (int64_t u = 24 * kSecond; u <= 31 * kSecond; u += 100'000) {
    in_.states.push_back({u, u >= 26 * kSecond && u < 29'500'000});
  }
  ev(30, EventType::kRelocalise, 101, 0);
  const LocalisationReport r = run();
  EXPECT_NEAR(r.instants.at(0).localising_s, 3.5, 1e-9);
  EXPECT_NEAR(r.localising_s, 3.5, 1e-9);
  in_.states.clear();  // without VITA_POSE: VITA_EVENT's state, held until the next event
  in_.events.back().localising = false;
  in_.events[in_.events.size() - 2].localising = true;  // 28 s: LOCALISING until the event at 30 s
  EXPECT_NEAR(run().instants.at(0).localising_s, 2.0, 1e-9);
}

TEST(LocalisingSession, ASessionOnASavedMapIsJudgedByTheFirstSessionsTruth) {
  // Session 1 made experiences 0..19 around the circle in its first 20 s; session 2 starts 1000 s
  // later where experience 7 was made.
  EvalInput in;
  in.map_ground_truth = circle_gt(20.0, 20.0);
  for (int i = 0; i < 20; ++i) in.map.experiences.push_back({i, Pose2{}, i * kSecond, false});
  constexpr int64_t k2 = 1000 * kSecond;
  for (int64_t u = 0; u <= 10 * kSecond; u += 20'000) in.ground_truth.push_back({k2 + u, circle_pose(u * 1e-6 + 7.0, 20.0)});
  int64_t cycle = 0;
  const auto ev = [&](double t_s, EventType type, int32_t from, int32_t to, bool localising) {
    in.events.push_back({k2 + std::llround(t_s * kSecond), ++cycle, type, from, to, localising});
    in.states.push_back({k2 + std::llround(t_s * kSecond), localising});
  };
  in.states.push_back({k2, true});
  ev(1, EventType::kSameExperience, 19, 19, true);  // where the map was saved: LOCALISING
  ev(2, EventType::kSameExperience, 19, 19, false);  // staying there is no claim
  ev(3, EventType::kRelocalise, 19, 10, false);     // at 3 s the robot is where 10 was made
  ev(4, EventType::kRelocalise, 10, 11, false);
  const LocalisationReport r = *evaluate(in, EvalParams{}).localisation;
  ASSERT_EQ(r.instants.size(), 1u) << "detected: the map is older than the log";
  const Localisation& l = r.instants[0];
  EXPECT_EQ(l.instant.kind, LocalisationInstant::Kind::kSessionStart);
  EXPECT_EQ(l.instant.utime, k2);
  ASSERT_TRUE(l.localised);
  EXPECT_EQ(l.localised_utime, k2 + 3 * kSecond);
  EXPECT_NEAR(*l.distance_m, 3.0 * kTwoPi / 20.0, 1e-3);
  EXPECT_NEAR(l.localising_s, 1.0 + 1.0, 1e-9) << "from the start to the event at 2 s";
  EXPECT_EQ(l.false_localisations, 0u);
  EXPECT_NEAR(*l.lem_after_m, 0.0, 1e-9);
  // Without the first session's truth the map's experiences cannot be judged: never localised.
  EvalInput blind = in;
  blind.map_ground_truth.clear();
  const Localisation b = evaluate(blind, EvalParams{}).localisation->instants.at(0);
  EXPECT_FALSE(b.localised);
  EXPECT_EQ(b.unjudged_events, 2u);
  // The first session's truth judges the rest of the metrics too, and nothing lies between the sessions.
  const EvalResult full = evaluate(in, EvalParams{});
  EXPECT_TRUE(full.alignment.valid);
  EXPECT_EQ(full.exm.relocalisations_total, 2u);
  EXPECT_EQ(full.exm.correct_total, 2u);
  EXPECT_FALSE(truth_of(in).at(500 * kSecond).has_value());
  EXPECT_TRUE(truth_of(in).at(10 * kSecond).has_value());
}

TEST(GroundTruth, IsNeverInterpolatedAcrossAKidnap) {
  const GroundTruth gt({{0, {0.0, 0.0, 0.0}}, {100, {2.0, 0.0, 1.0}}, {200, {2.0, 1.0, 1.0}}}, {50});
  EXPECT_EQ(gt.at(49)->x, 0.0) << "before the jump: the sample before it";
  EXPECT_EQ(gt.at(50)->x, 2.0) << "at and after it: the sample after it";
  EXPECT_NEAR(gt.at(150)->y, 0.5, 1e-12) << "elsewhere interpolated";
  EXPECT_TRUE(gt.breaks_between(0, 100));
  EXPECT_FALSE(gt.breaks_between(50, 200));
  EXPECT_NEAR(gt.path_length(0, 200), 1.0, 1e-12) << "the jump is no travel";
  EXPECT_NEAR(gt.path_length(50, 150), 0.5, 1e-12);
}

}  // namespace
}  // namespace whiskeye::eval
