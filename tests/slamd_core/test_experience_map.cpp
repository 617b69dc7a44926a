// Experience map: relaxation of a drifting loop, the action rule, checkpoints.
#include "whiskeye/slam/experience_map.h"

#include "whiskeye/slam/pose_cells.h"
#include "whiskeye/slam/vita_slam.h"

#include "old_formats.h"

#include <gtest/gtest.h>

#include <cstring>
#include <limits>

namespace whiskeye::slam {
namespace {

double link_residual_pos(const ExperienceMap& m, const Link& l) {
  const auto& e = m.experiences();
  const Pose2 pred = compose(e[static_cast<size_t>(l.from)].pose, l.delta);
  return std::hypot(pred.x - e[static_cast<size_t>(l.to)].pose.x, pred.y - e[static_cast<size_t>(l.to)].pose.y);
}

TEST(ExperienceMap, RelaxationTurnsADriftingSquareLoopIntoASquare) {
  // A 2 m square driven in 40 steps of 0.2 m, turning 90° at each corner. Odometry turns 0.012 rad
  // too much per step and overestimates distance by 3 %.
  ExperienceMap m;
  std::vector<Pose2> truth_steps;
  Pose2 dr;  // dead reckoning
  const int per_side = 10;
  m.add_experience(dr, Experience{});
  for (int i = 1; i < 4 * per_side; ++i) {
    const bool corner = i % per_side == 0;
    const Pose2 truth{0.2, 0.0, corner ? kPi / 2 : 0.0};
    const Pose2 measured{0.2 * 1.03, 0.0, truth.theta + 0.012};
    dr = compose(dr, measured);
    m.add_experience(dr, Experience{});
    m.add_link(i - 1, i, measured, i);
  }
  // Back at the start: the loop closure link carries the true relative pose (last → first).
  m.add_link(4 * per_side - 1, 0, Pose2{0.2, 0.0, kPi / 2}, 99);
  const Link closure = m.links().back();
  const double before = link_residual_pos(m, closure);
  ASSERT_GT(before, 0.5);  // the drift is real

  m.relax(3000);
  EXPECT_LT(link_residual_pos(m, closure), 0.1 * before);
  double worst = 0.0;
  for (const Link& l : m.links()) worst = std::max(worst, link_residual_pos(m, l));
  EXPECT_LT(worst, 0.05);

  const auto& e = m.experiences();
  const Pose2 c[4] = {e[0].pose, e[10].pose, e[20].pose, e[30].pose};
  auto d = [](const Pose2& a, const Pose2& b) { return std::hypot(a.x - b.x, a.y - b.y); };
  const double sides[4] = {d(c[0], c[1]), d(c[1], c[2]), d(c[2], c[3]), d(c[3], c[0])};
  for (double s : sides) EXPECT_NEAR(s, 2.0 * 1.03, 0.15);
  EXPECT_NEAR(d(c[0], c[2]), d(c[1], c[3]), 0.1);  // equal diagonals: a square, not a rhombus
  EXPECT_NEAR(d(c[0], c[2]), 2.0 * 1.03 * std::sqrt(2.0), 0.2);
}

// A ring of 40 experiences 0.1 m apart driven once (odometry exact), then closed twice: once
// correctly and once onto a place 1.5 m away (a look-alike). The wrong link is revoked by the rest
// of the map (its scale all but gone), the right one keeps its pull, and the ring keeps its shape.
TEST(ExperienceMap, AClosureTheRestOfTheMapDisagreesWithIsRevokedAndTheMapKeepsItsShape) {
  ExperienceMap m;
  const int n = 40;
  const double step = kTwoPi / n;
  const auto ring = [&](int i) { return Pose2{std::cos(i * step), std::sin(i * step), wrap_angle(i * step + kPi / 2)}; };
  for (int i = 0; i < n; ++i) {
    m.add_experience(ring(i), Experience{});
    if (i > 0) m.add_link(i - 1, i, between(ring(i - 1), ring(i)), i);
  }
  m.add_link(n - 1, 0, between(ring(n - 1), ring(0)), 100, 1);  // the lap closed where it is
  // From experience 10 "recognised" as experience 25 (1.5 m away), with the odometry of one step.
  m.add_link(10, 25, between(ring(10), ring(11)), 101, 1);
  m.relax(2000);
  const std::vector<Link>& links = m.links();
  EXPECT_TRUE(links[links.size() - 1].revoked()) << links.back().scale;
  EXPECT_FALSE(links[links.size() - 2].revoked());
  EXPECT_GT(links[links.size() - 2].scale, 0.9);
  for (std::size_t l = 0; l + 2 < links.size(); ++l) EXPECT_EQ(links[l].scale, 1.0) << "odometry is not robust";
  double worst = 0.0;
  for (int i = 0; i < n; ++i) {
    const Pose2& p = m.experiences()[static_cast<size_t>(i)].pose;
    worst = std::max(worst, std::hypot(p.x - ring(i).x, p.y - ring(i).y));
  }
  EXPECT_LT(worst, 0.05) << "a wrong closure that kept its pull bends the ring by decimetres";
  // Without the scaling (robust_phi 0, here set on the map made) the same wrong link bends it.
  ExperienceMapParams off;
  off.robust_phi = 0.0;
  m.set_params(off);
  m.relax(2000);
  EXPECT_FALSE(m.links().back().revoked());
  EXPECT_GT(std::hypot(m.experiences()[10].pose.x - ring(10).x, m.experiences()[10].pose.y - ring(10).y), 0.1);
}

// The shipped σ's make a ring of odometry soft: bending it a metre costs less than a robust link's
// whole bounded cost, so wrong closures that keep any pull at all (DCS weakens, it never zeroes)
// bend it over the loops, and the more of them the surer. A wrong closure beyond the drift budget it
// was made within has none: 80 of them, as many as the ring has links, leave the ring as it was.
TEST(ExperienceMap, WrongClosuresBeyondTheirGateHaveNoPullHoweverMany) {
  const int n = 80;
  const double step = kTwoPi / n;
  const auto ring = [&](int i) { return Pose2{std::cos(i * step), std::sin(i * step), wrap_angle(i * step + kPi / 2)}; };
  const auto worst_after = [&](double gate_m, int* kept) {
    ExperienceMap m;  // shipped parameters
    for (int i = 0; i < n; ++i) {
      m.add_experience(ring(i), Experience{});
      if (i > 0) m.add_link(i - 1, i, between(ring(i - 1), ring(i)), i);
    }
    m.add_link(n - 1, 0, between(ring(n - 1), ring(0)), 100, 1, gate_m);  // the lap closed where it is
    for (int i = 0; i < n; ++i) {  // each experience "recognised" as the one across the ring (2 m away)
      m.add_link(i, (i + n / 2 + 3) % n, Pose2{}, 200 + i, 1, gate_m);
    }
    for (int k = 0; k < 50; ++k) m.relax(20);  // 50 cycles' relaxation
    *kept = 0;
    for (size_t l = static_cast<size_t>(n); l < m.links().size(); ++l) *kept += m.links()[l].revoked() ? 0 : 1;
    double worst = 0.0;
    for (int i = 0; i < n; ++i) {
      const Pose2& p = m.experiences()[static_cast<size_t>(i)].pose;
      worst = std::max(worst, std::hypot(p.x - ring(i).x, p.y - ring(i).y));
    }
    return worst;
  };
  int kept = 0;
  EXPECT_LT(worst_after(0.3, &kept), 0.01);
  EXPECT_EQ(kept, 0) << "every wrong closure revoked";
  // Without a gate (DCS alone) the same closures fold the ring.
  EXPECT_GT(worst_after(std::numeric_limits<double>::infinity(), &kept), 0.1);
}

// A closure made within its gate keeps its pull as the map comes to agree with it, and a link whose
// residual leaves its gate regains it when the map comes back (revocable, not deleted).
TEST(ExperienceMap, AGatedLinkRegainsItsPullWhenTheMapComesWithinItsGate) {
  ExperienceMap m;
  m.add_experience({0, 0, 0}, Experience{});
  m.add_experience({0.1, 0, 0}, Experience{});
  m.add_experience({0.5, 0, 0}, Experience{});
  m.add_link(0, 1, {0.1, 0, 0}, 0);
  m.add_link(1, 2, {0.1, 0, 0}, 0, 1, 0.2);  // says 2 is at 0.2 m: 0.3 m off, beyond its gate
  EXPECT_TRUE(m.links()[1].revoked()) << "judged when made: a map published before the next relaxation shows it";
  m.relax(100);
  EXPECT_TRUE(m.links()[1].revoked());
  EXPECT_NEAR(m.experiences()[2].pose.x, 0.5, 1e-12) << "no pull while revoked";
  m.add_link(0, 2, {0.3, 0, 0}, 1);  // odometry puts it at 0.3 m: within the gate again
  m.relax(2000);
  EXPECT_FALSE(m.links()[1].revoked());
  EXPECT_GT(m.links()[1].scale, 0.9);
}

// A link's weight is its information: odometry between places the robot was at is precise, an end
// it only recognised is up to half the experience spacing off. Two links disagree by 0.1 m about
// where experience 1 is: the odometry links' (σ 0.002 m here) win over the re-localisation's (σ about
// place_sigma_m), where every link counted alike (the mean: 0.05 m off each).
TEST(ExperienceMap, ALinkToARecognisedPlacePullsLessThanOdometryBetweenPlacesTheRobotWasAt) {
  ExperienceMapParams p;
  p.robust_phi = 0.0;  // the weights alone
  p.odometry_sigma_per_m = 0.02;
  p.odometry_sigma_min_m = 0.002;
  p.place_sigma_m = 0.03;
  // Three experiences 0.1 m apart, the re-localisation's link saying the third is where the second is.
  const auto relaxed_span = [](const ExperienceMapParams& params, std::vector<Link>* links = nullptr) {
    ExperienceMap m(params);
    m.add_experience({0, 0, 0}, Experience{});
    m.add_experience({0.1, 0, 0}, Experience{});
    m.add_experience({0.2, 0, 0}, Experience{});
    m.add_link(0, 1, {0.1, 0, 0}, 0);
    m.add_link(1, 2, {0.1, 0, 0}, 0);
    m.add_link(0, 2, {0.1, 0, 0}, 0, 1);
    m.relax(500);
    if (links != nullptr) *links = m.links();
    return m.experiences()[2].pose.x - m.experiences()[0].pose.x;
  };
  std::vector<Link> links;
  EXPECT_NEAR(relaxed_span(p, &links), 0.2, 0.01);
  EXPECT_NEAR(links[0].sigma2, 0.002 * 0.002, 1e-12);
  EXPECT_NEAR(links[2].sigma2, 0.002 * 0.002 + 0.03 * 0.03, 1e-12);
  // Weighted alike (place_sigma_m 0, a constant σ): the three links share the error.
  ExperienceMapParams alike = p;
  alike.place_sigma_m = 0.0;
  alike.odometry_sigma_per_m = 0.0;
  EXPECT_LT(relaxed_span(alike), 0.15);
}

// Both ends of a link move by `correction` x its error: at 0.5 one loop closes a lone link, above it
// the pair overshoots (at 1 it swung between +0.2 m and -0.2 m for ever), so the loader stops at 0.5
// (SlamParams.LoadFromTheShippedConfigAndRejectUnknownKeys: this file also builds for aarch64, without the loaders).
TEST(ExperienceMap, CorrectionOneHalfClosesALoneLinkInOneLoop) {
  ExperienceMapParams p;
  p.correction = 0.5;
  ExperienceMap m(p);
  m.add_experience({0, 0, 0}, Experience{});
  m.add_experience({1.2, 0, 0}, Experience{});
  m.add_link(0, 1, {1.0, 0, 0}, 0);  // 0.2 m of error
  m.relax(1);
  EXPECT_NEAR(m.experiences()[1].pose.x - m.experiences()[0].pose.x, 1.0, 1e-9);
}

TEST(ExperienceMap, RelaxationKeepsAConsistentMapUnchanged) {
  ExperienceMap m;
  m.add_experience({0, 0, 0}, Experience{});
  m.add_experience({1, 0, kPi / 2}, Experience{});
  m.add_experience({1, 1, kPi}, Experience{});
  m.add_link(0, 1, {1, 0, kPi / 2}, 0);
  m.add_link(1, 2, {1, 0, kPi / 2}, 0);
  m.relax(50);
  EXPECT_NEAR(m.experiences()[2].pose.x, 1.0, 1e-9);
  EXPECT_NEAR(m.experiences()[2].pose.y, 1.0, 1e-9);
  EXPECT_NEAR(std::abs(m.experiences()[2].pose.theta), kPi, 1e-9);
}

// The classic RatSLAM rule: the pose cells decide (the odometry-consistency gate off).
ExperienceMapParams pose_cell_rule(ExperienceMapParams p = {}) {
  p.drift_per_m = 1000.0;
  return p;
}

TEST(ExperienceMap, ActionRuleCreatesLinksAndRelocalises) {
  const PoseCells cells{PoseCellParams{}};
  ExperienceMap m(pose_cell_rule());
  // Cycle 1: template 0 at pc (10, 10, 0) → first experience.
  Event e = m.on_cycle({.template_id = 0, .visual_template_id = 0, .pc_x = 10, .pc_y = 10, .utime = 1000}, cells);
  EXPECT_EQ(e.type, EventType::NewExperience);
  EXPECT_EQ(e.from_id, -1);
  EXPECT_EQ(e.to_id, 0);
  EXPECT_EQ(m.experiences()[0].utime_created, 1000);
  EXPECT_EQ(m.experiences()[0].visual_template_id, 0);
  EXPECT_EQ(m.experiences()[0].tactile_template_id, -1);
  // Move 1 m; a new template → new experience linked from the first.
  m.integrate(1.0, 0.0, 0.0, 1.0);
  e = m.on_cycle({.template_id = 1, .visual_template_id = 1, .tactile_template_id = 1, .dense = true, .pc_x = 15, .pc_y = 10, .utime = 2000}, cells);
  EXPECT_EQ(e.type, EventType::NewExperience);
  EXPECT_EQ(e.from_id, 0);
  EXPECT_EQ(e.to_id, 1);
  EXPECT_NEAR(m.experiences()[1].pose.x, 1.0, 1e-12);
  EXPECT_TRUE(m.experiences()[1].dense);
  // The same template with the pose cells still there: nothing changes.
  m.integrate(0.1, 0.0, 0.0, 1.0);
  e = m.on_cycle({.template_id = 1, .visual_template_id = 1, .tactile_template_id = 1, .dense = true, .pc_x = 15.5, .pc_y = 10, .utime = 2500}, cells);
  EXPECT_EQ(e.type, EventType::SameExperience);
  // A third place.
  m.integrate(1.0, 0.0, 0.0, 1.0);
  e = m.on_cycle({.template_id = 2, .visual_template_id = 2, .tactile_template_id = 2, .dense = true, .pc_x = 20, .pc_y = 10, .utime = 2800}, cells);
  EXPECT_EQ(e.type, EventType::NewExperience);
  // Template 0 seen again with the pose cells back near its cells → re-localise onto experience 0
  // with a new link carrying the odometry.
  m.integrate(-2.0, 0.0, 0.0, 1.0);
  e = m.on_cycle({.template_id = 0, .visual_template_id = 0, .pc_x = 10.5, .pc_y = 10, .utime = 3000}, cells);
  EXPECT_EQ(e.type, EventType::Relocalise);
  EXPECT_EQ(e.from_id, 2);
  EXPECT_EQ(e.to_id, 0);
  EXPECT_EQ(m.current_id(), 0);
  ASSERT_EQ(m.links().size(), 3u);
  EXPECT_EQ(m.links()[2].from, 2);
  EXPECT_EQ(m.links()[2].to, 0);
  EXPECT_NEAR(m.links()[2].delta.x, -2.0, 1e-12);
  EXPECT_EQ(m.offset(), Pose2{});
  // Template 0 seen where the pose cells are far from its experience → a new experience.
  e = m.on_cycle({.template_id = 0, .visual_template_id = 0, .pc_x = 2, .pc_y = 3, .pc_theta = 18, .utime = 4000}, cells);
  EXPECT_EQ(e.type, EventType::NewExperience);
  EXPECT_EQ(m.size(), 4);
}

// A cycle without one of its mode's senses (VitaSlam's degraded cycle) may re-localise onto a known
// experience but never creates one.
TEST(ExperienceMap, ADegradedCycleReLocalisesButNeverCreates) {
  const PoseCells cells{PoseCellParams{}};
  ExperienceMap m(pose_cell_rule());
  m.on_cycle({.template_id = 0, .visual_template_id = 0, .tactile_template_id = 0, .dense = true, .pc_x = 10, .pc_y = 10, .utime = 1000}, cells);
  m.integrate(1.0, 0.0, 0.0, 1.0);
  m.on_cycle({.template_id = 1, .visual_template_id = 1, .tactile_template_id = 1, .dense = true, .pc_x = 15, .pc_y = 10, .utime = 2000}, cells);
  // A template without experiences, and one whose experience is beyond the pose cells' reach.
  m.integrate(1.0, 0.0, 0.0, 1.0);
  EXPECT_EQ(m.on_cycle({.template_id = 2, .visual_template_id = 2, .tactile_template_id = 2, .dense = true, .pc_x = 20, .pc_y = 10, .utime = 3000, .degraded = true}, cells).type, EventType::SameExperience);
  EXPECT_EQ(m.on_cycle({.template_id = 0, .visual_template_id = 0, .tactile_template_id = 0, .dense = true, .pc_x = 20, .pc_y = 10, .utime = 3100, .degraded = true}, cells).type, EventType::SameExperience);
  EXPECT_EQ(m.size(), 2);
  EXPECT_EQ(m.links().size(), 1u);
  EXPECT_EQ(m.current_id(), 1);
  EXPECT_NEAR(m.current_pose().x, 2.0, 1e-12);  // the odometry goes on
  // A known place within reach: re-localised as by a full cycle.
  const Event e = m.on_cycle({.template_id = 0, .visual_template_id = 0, .tactile_template_id = 0, .dense = true, .pc_x = 10.4, .pc_y = 10, .utime = 3200, .degraded = true}, cells);
  EXPECT_EQ(e.type, EventType::Relocalise);
  EXPECT_EQ(e.to_id, 0);
  // Without the flag the same unseen template makes an experience.
  EXPECT_EQ(m.on_cycle({.template_id = 2, .visual_template_id = 2, .tactile_template_id = 2, .dense = true, .pc_x = 20, .pc_y = 10, .utime = 3300}, cells).type, EventType::NewExperience);
}

TEST(ExperienceMap, ViewTurnedBeyondMaxViewShiftIsANewExperienceOfTheSameTemplate) {
  const PoseCells cells{PoseCellParams{}};
  ExperienceMapParams p;
  p.max_view_shift = 2;
  p.distinct_places = 0;  // every template counts as aliased: max_view_shift applies throughout
  ExperienceMap m(pose_cell_rule(p));
  m.on_cycle({.template_id = 0, .visual_template_id = 0, .pc_x = 10, .pc_y = 10, .utime = 1000}, cells);  // experience 0, template 0, shift 0
  m.integrate(0.5, 0.0, 0.0, 1.0);
  m.on_cycle({.template_id = 1, .visual_template_id = 1, .pc_x = 15, .pc_y = 10, .utime = 2000}, cells);  // experience 1
  // Template 0 again, pose cells at its experience, but the view is turned by 4 columns: the same
  // place from another pose → a new experience of template 0 that remembers the shift.
  m.integrate(-0.5, 0.0, 0.0, 1.0);
  Event e = m.on_cycle({.template_id = 0, .visual_template_id = 0, .pc_x = 10.2, .pc_y = 10, .utime = 3000, .view_shift = 4}, cells);
  EXPECT_EQ(e.type, EventType::NewExperience);
  EXPECT_EQ(e.to_id, 2);
  EXPECT_EQ(m.experiences()[2].template_id, 0);
  EXPECT_EQ(m.experiences()[2].view_shift, 4);
  m.integrate(0.5, 0.0, 0.0, 1.0);
  m.on_cycle({.template_id = 1, .visual_template_id = 1, .pc_x = 15, .pc_y = 10, .utime = 4000}, cells);  // back to experience 1
  // Seen again with shift 3: within 2 of experience 2's shift (4), not of experience 0's (0), so it
  // re-localises onto experience 2 although experience 0 is as near in the pose cells.
  m.integrate(-0.5, 0.0, 0.0, 1.0);
  e = m.on_cycle({.template_id = 0, .visual_template_id = 0, .pc_x = 10.1, .pc_y = 10, .utime = 5000, .view_shift = 3}, cells);
  EXPECT_EQ(e.type, EventType::Relocalise);
  EXPECT_EQ(e.to_id, 2);
  // Within the limit of experience 0's shift: onto experience 0.
  m.integrate(0.5, 0.0, 0.0, 1.0);
  m.on_cycle({.template_id = 1, .visual_template_id = 1, .pc_x = 15, .pc_y = 10, .utime = 6000}, cells);
  m.integrate(-0.5, 0.0, 0.0, 1.0);
  e = m.on_cycle({.template_id = 0, .visual_template_id = 0, .pc_x = 10.0, .pc_y = 10, .utime = 7000, .view_shift = -1}, cells);
  EXPECT_EQ(e.type, EventType::Relocalise);
  EXPECT_EQ(e.to_id, 0);
  // Frozen (localisation only): the shift does not matter, nothing is created.
  m.set_frozen(true);
  m.integrate(0.5, 0.0, 0.0, 1.0);
  m.on_cycle({.template_id = 1, .visual_template_id = 1, .pc_x = 15, .pc_y = 10, .utime = 8000}, cells);
  m.integrate(-0.5, 0.0, 0.0, 1.0);
  e = m.on_cycle({.template_id = 0, .visual_template_id = 0, .pc_x = 10.0, .pc_y = 10, .utime = 9000, .view_shift = 5}, cells);
  EXPECT_EQ(e.type, EventType::Relocalise);
  EXPECT_EQ(m.size(), 3);
}

TEST(ExperienceMap, ADistinctiveTemplateReLocalisesFromAWiderViewShiftThanAnAliasedOne) {
  const PoseCells cells{PoseCellParams{}};
  ExperienceMapParams p;
  p.max_view_shift = 2;
  p.max_view_shift_distinct = 4;
  p.distinct_places = 1;
  ExperienceMap m(pose_cell_rule(p));
  // Template 0 at one place (distinctive), template 1 at two places (aliased), template 2 elsewhere.
  m.on_cycle({.template_id = 0, .visual_template_id = 0, .pc_x = 10, .pc_y = 10, .utime = 1000}, cells);  // experience 0, template 0
  m.integrate(0.5, 0.0, 0.0, 1.0);
  m.on_cycle({.template_id = 1, .visual_template_id = 1, .pc_x = 15, .pc_y = 10, .utime = 2000}, cells);  // experience 1, template 1
  m.integrate(0.5, 0.0, 0.0, 1.0);
  m.on_cycle({.template_id = 2, .visual_template_id = 2, .pc_x = 20, .pc_y = 10, .utime = 3000}, cells);  // experience 2, template 2
  m.integrate(0.5, 0.0, 0.0, 1.0);
  m.on_cycle({.template_id = 1, .visual_template_id = 1, .pc_x = 10, .pc_y = 18, .pc_theta = 9, .utime = 4000}, cells);  // experience 3: template 1 again, far away
  ASSERT_EQ(m.size(), 4);
  // Back near experience 0 with the view turned by 4 columns: distinctive, so it re-localises.
  m.integrate(-0.5, 0.0, 0.0, 1.0);
  Event e = m.on_cycle({.template_id = 0, .visual_template_id = 0, .pc_x = 10.1, .pc_y = 10, .utime = 5000, .view_shift = 4}, cells);
  EXPECT_EQ(e.type, EventType::Relocalise);
  EXPECT_EQ(e.to_id, 0);
  // 5 columns is beyond even the distinctive limit: a new experience of template 0.
  m.integrate(0.5, 0.0, 0.0, 1.0);
  m.on_cycle({.template_id = 2, .visual_template_id = 2, .pc_x = 20, .pc_y = 10, .utime = 6000}, cells);
  m.integrate(-0.5, 0.0, 0.0, 1.0);
  e = m.on_cycle({.template_id = 0, .visual_template_id = 0, .pc_x = 10.1, .pc_y = 10, .utime = 7000, .view_shift = 5}, cells);
  EXPECT_EQ(e.type, EventType::NewExperience);
  ASSERT_EQ(m.size(), 5);  // experience 4; template 0 now has two places
  // Template 1 (two places: aliased) at experience 1 with 3 columns: beyond max_view_shift → new.
  m.integrate(0.5, 0.0, 0.0, 1.0);
  e = m.on_cycle({.template_id = 1, .visual_template_id = 1, .pc_x = 15, .pc_y = 10, .utime = 8000, .view_shift = 3}, cells);
  EXPECT_EQ(e.type, EventType::NewExperience);
  // ... and with 2 columns it re-localises onto experience 1.
  m.integrate(0.5, 0.0, 0.0, 1.0);
  m.on_cycle({.template_id = 2, .visual_template_id = 2, .pc_x = 20, .pc_y = 10, .utime = 9000}, cells);
  m.integrate(-0.5, 0.0, 0.0, 1.0);
  e = m.on_cycle({.template_id = 1, .visual_template_id = 1, .pc_x = 15, .pc_y = 10, .utime = 10000, .view_shift = 2}, cells);
  EXPECT_EQ(e.type, EventType::Relocalise);
  EXPECT_EQ(e.to_id, 1);
}

// ---- the odometry-consistency gate and the local refinement (docs/slam-core.md) ----

// Experiences 0..n-1 along x, `spacing` apart, template i at experience i, the pose cells' packet
// at the origin throughout (they are not what decides here).
ExperienceMap line_of_experiences(const ExperienceMapParams& p, int n, double spacing, const PoseCells& cells) {
  ExperienceMap m(p);
  for (int i = 0; i < n; ++i) {
    if (i > 0) m.integrate(spacing, 0.0, 0.0, 1.0);
    m.on_cycle({.template_id = i, .visual_template_id = i, .utime = 1000 * (i + 1)}, cells);
  }
  return m;
}

TEST(ExperienceMap, ALookAlikePlaceFartherThanOdometryCanHaveDriftedIsNotClosedOnto) {
  const PoseCells cells{PoseCellParams{}};
  ExperienceMapParams p;
  p.drift_base = 0.25;
  p.drift_per_m = 0.1;
  // Experience 0 at the origin, then 2 m away in 0.5 m steps (the pose cells see no difference:
  // a 2.1 m wrap-around grid puts a place 2.1 m away next to this one).
  ExperienceMap m = line_of_experiences(p, 5, 0.5, cells);
  ASSERT_EQ(m.current_id(), 4);
  m.integrate(0.1, 0.0, 0.0, 1.0);
  // 2.1 m from experience 0 after 2.1 m of travel: the budget is 0.25 + 0.21 m.
  EXPECT_NEAR(m.drift_budget(), 0.46, 1e-12);
  const Event e = m.on_cycle({.template_id = 0, .visual_template_id = 0, .utime = 9000}, cells);
  EXPECT_EQ(e.type, EventType::NewExperience);
  EXPECT_EQ(m.experiences()[5].template_id, 0);
  // The RatSLAM rule (pose cells alone) closes that loop.
  ExperienceMap r = line_of_experiences(pose_cell_rule(p), 5, 0.5, cells);
  r.integrate(0.1, 0.0, 0.0, 1.0);
  EXPECT_EQ(r.on_cycle({.template_id = 0, .visual_template_id = 0, .utime = 9000}, cells).type, EventType::Relocalise);
}

TEST(ExperienceMap, TheDriftBudgetGrowsWithTheDistanceTravelledAndRestartsAtAReLocalisation) {
  const PoseCells cells{PoseCellParams{}};
  ExperienceMapParams p;
  p.drift_base = 0.25;
  p.drift_per_m = 0.1;
  ExperienceMap m = line_of_experiences(p, 2, 0.5, cells);
  // Around a 10 m loop that odometry closes 0.6 m off: 0.25 + 0.1 · 10.5 m ≥ 0.6 m, closed.
  for (int i = 0; i < 100; ++i) m.integrate(0.1, 0.0, kPi / 50.0, 1.0);  // a circle of r = 1.59 m
  m.integrate(0.0, 0.6, 0.0, 1.0);                                     // plus 0.6 m of drift
  EXPECT_GT(m.drift_budget(), 0.6);
  // Template 0 (experience 0, 0.5 m behind the start, 0.78 m from here).
  const Event e = m.on_cycle({.template_id = 0, .visual_template_id = 0, .utime = 9000}, cells);
  EXPECT_EQ(e.type, EventType::Relocalise);
  EXPECT_EQ(e.to_id, 0);
  EXPECT_DOUBLE_EQ(m.travel_since_relocalisation(), 0.0);
  EXPECT_DOUBLE_EQ(m.drift_budget(), 0.25);
}

TEST(ExperienceMap, ReLocalisesOntoTheNearestOfTheTemplatesExperiencesInTheMap) {
  const PoseCells cells{PoseCellParams{}};
  ExperienceMapParams p;
  p.drift_per_m = 1.0;
  ExperienceMap m(p);
  m.on_cycle({.template_id = 0, .visual_template_id = 0, .utime = 1000}, cells);  // experience 0, template 0, at x = 0
  m.integrate(0.5, 0.0, 0.0, 1.0);
  m.on_cycle({.template_id = 1, .visual_template_id = 1, .utime = 2000}, cells);  // experience 1, template 1, at 0.5
  m.integrate(0.5, 0.0, 0.0, 1.0);
  m.on_cycle({.template_id = 0, .visual_template_id = 0, .utime = 3000}, cells);  // template 0 again at 1.0: budget 0.25 + 1 → ...
  ASSERT_EQ(m.current_id(), 0);                        // ... closed onto experience 0 (1 m back)
  m.integrate(1.0, 0.0, 0.0, 1.0);
  m.on_cycle({.template_id = 2, .visual_template_id = 2, .utime = 4000}, cells);   // experience 2 at 1.0 (from experience 0)
  m.integrate(0.1, 0.0, 0.0, 1.0);
  // Template 1 is at experience 1 only; template 0 at experience 0. Add a second experience of
  // template 0 next to here, by the view-shift rule (another pose of the same place).
  m.on_cycle({.template_id = 0, .visual_template_id = 0, .utime = 5000, .view_shift = 5}, cells);
  ASSERT_EQ(m.size(), 4);
  EXPECT_NEAR(m.experiences()[3].pose.x, 1.1, 1e-9);
  m.integrate(0.05, 0.0, 0.0, 1.0);
  m.on_cycle({.template_id = 2, .visual_template_id = 2, .utime = 6000}, cells);  // back onto experience 2 (0.15 m away)
  ASSERT_EQ(m.current_id(), 2);
  m.integrate(0.12, 0.0, 0.0, 1.0);                   // at 1.12: experience 3 is 2 cm away, 0 is 1.12 m
  const Event e = m.on_cycle({.template_id = 0, .visual_template_id = 0, .utime = 7000, .view_shift = 4}, cells);
  EXPECT_EQ(e.type, EventType::Relocalise);
  EXPECT_EQ(e.to_id, 3);
}

TEST(ExperienceMap, ThePoseCellsChooseWhileTheRobotRecognisesPlacesAndTheMapAfterALongStretch) {
  const PoseCells cells{PoseCellParams{}};
  ExperienceMapParams p;
  p.drift_base = 0.5;
  p.drift_per_m = 0.1;
  p.packet_trust_m = 1.0;
  // Experience 0 at the origin (pose cells at (10, 10)), experience 1 at 0.3 m (cells (13, 10)).
  ExperienceMap m(p);
  m.on_cycle({.template_id = 0, .visual_template_id = 0, .pc_x = 10, .pc_y = 10, .utime = 1000}, cells);
  m.integrate(0.3, 0.0, 0.0, 1.0);
  m.on_cycle({.template_id = 1, .visual_template_id = 1, .pc_x = 13, .pc_y = 10, .utime = 2000}, cells);
  // Template 0 again 0.3 m on, with the packet 5 cells from experience 0's: within the map's budget,
  // but the robot has travelled less than packet_trust_m, so the packet decides: a new experience.
  m.integrate(0.3, 0.0, 0.0, 1.0);
  Event e = m.on_cycle({.template_id = 0, .visual_template_id = 0, .pc_x = 15, .pc_y = 10, .utime = 3000}, cells);
  EXPECT_EQ(e.type, EventType::NewExperience);
  // The same after 2 m without recognising anything (the packet may have drifted away): the map
  // decides, and experience 0 is within its budget (0.5 + 0.2 m).
  for (int i = 0; i < 4; ++i) m.integrate(0.5, 0.0, 0.0, 1.0);
  m.integrate(-2.6, 0.05, 0.0, 1.0);  // back near the origin, 2.6 m more travelled
  e = m.on_cycle({.template_id = 0, .visual_template_id = 0, .pc_x = 15, .pc_y = 10, .utime = 4000}, cells);
  EXPECT_EQ(e.type, EventType::Relocalise);
  EXPECT_EQ(e.to_id, 0);
}

TEST(ExperienceMap, ReadsOlderCheckpointsWithoutViewShiftsTravelOrRetiredFlags) {
  const PoseCells cells{PoseCellParams{}};
  ExperienceMap m;
  m.on_cycle({.template_id = 0, .visual_template_id = 0, .tactile_template_id = 0, .dense = true, .pc_x = 10, .pc_y = 10, .utime = 1}, cells);
  std::vector<uint8_t> now;
  m.serialise(now);
  const std::vector<uint8_t> v4 = testing::map_as_format_5(now);
  ASSERT_EQ(v4.size(), now.size() - 1);  // no link: only the "current recognised" flag
  // Version 3 is version 4 without the u8 retired flag after the view shift: 8 bytes of count, then
  // 7 f64, i64, 3 i32, u8, i32 for the one experience.
  std::vector<uint8_t> v3 = v4;
  const size_t retired_at = 8 + 7 * 8 + 8 + 3 * 4 + 1 + 4;
  v3.erase(v3.begin() + static_cast<std::ptrdiff_t>(retired_at));
  // Version 2 is version 3 without the travelled distance at the end (0 here: nothing travelled).
  const std::vector<uint8_t> v2(v3.begin(), v3.end() - 8);
  // Version 1 is version 2 without the i32 view shift after the dense flag.
  std::vector<uint8_t> v1 = v2;
  const size_t shift_at = 8 + 7 * 8 + 8 + 3 * 4 + 1;
  v1.erase(v1.begin() + static_cast<std::ptrdiff_t>(shift_at), v1.begin() + static_cast<std::ptrdiff_t>(shift_at + 4));
  ExperienceMap r;
  size_t pos = 0;
  r.deserialise(v1, pos, 1, 1);
  EXPECT_EQ(pos, v1.size());
  ASSERT_EQ(r.size(), 1);
  EXPECT_EQ(r.experiences()[0].view_shift, 0);
  std::vector<uint8_t> again;
  r.serialise(again);
  EXPECT_EQ(again, now);
  ExperienceMap r4;
  pos = 0;
  r4.deserialise(v4, pos, 4, 1);
  EXPECT_EQ(pos, v4.size());
  ExperienceMap r3;
  pos = 0;
  r3.deserialise(v3, pos, 3, 1);
  EXPECT_EQ(pos, v3.size());
  EXPECT_FALSE(r3.experiences()[0].retired);
  ExperienceMap r2;
  pos = 0;
  r2.deserialise(v2, pos, 2, 1);
  EXPECT_EQ(pos, v2.size());
  EXPECT_DOUBLE_EQ(r2.travel_since_relocalisation(), 0.0);
}

// A map saved before links had recognised ends: a link made after its `to` experience is a
// re-localisation's (one end recognised, robust); a link made with its `to` is odometry's.
TEST(ExperienceMap, ReadsLinksOfAnOlderCheckpointAsOdometryOrAReLocalisationsByTheirTimes) {
  const PoseCells cells{PoseCellParams{}};
  ExperienceMap m;
  m.on_cycle({.template_id = 0, .visual_template_id = 0, .utime = 1000}, cells);  // experience 0
  m.integrate(0.1, 0.0, 0.0, 1.0);
  m.on_cycle({.template_id = 1, .visual_template_id = 1, .utime = 2000}, cells);  // experience 1, link 0 -> 1
  m.integrate(0.1, 0.0, 0.0, 1.0);
  m.on_cycle({.template_id = 2, .visual_template_id = 2, .utime = 3000}, cells);  // experience 2, link 1 -> 2
  m.integrate(-0.15, 0.0, 0.0, 1.0);
  ASSERT_EQ(m.on_cycle({.template_id = 0, .visual_template_id = 0, .utime = 4000}, cells).type, EventType::Relocalise);  // back onto 0
  m.integrate(0.1, 0.0, 0.0, 1.0);
  const Event next = m.on_cycle({.template_id = 3, .visual_template_id = 3, .utime = 5000}, cells);  // experience 3 from a recognised one
  ASSERT_EQ(next.type, EventType::NewExperience);
  ASSERT_EQ(m.links().size(), 4u);
  EXPECT_EQ(m.links()[0].recognised_ends, 0);
  EXPECT_EQ(m.links()[1].recognised_ends, 0);
  EXPECT_EQ(m.links()[2].recognised_ends, 1);  // 2 -> 0: the re-localisation's end
  EXPECT_EQ(m.links()[3].recognised_ends, 1);  // 0 -> 3: from where it only recognised itself
  std::vector<uint8_t> now;
  m.serialise(now);
  const std::vector<uint8_t> v5 = testing::map_as_format_5(now);
  ExperienceMap r;
  size_t pos = 0;
  r.deserialise(v5, pos, 5, 4);
  EXPECT_EQ(pos, v5.size());
  ASSERT_EQ(r.links().size(), 4u);
  EXPECT_EQ(r.links()[0].recognised_ends, 0);
  EXPECT_EQ(r.links()[1].recognised_ends, 0);
  EXPECT_EQ(r.links()[2].recognised_ends, 1);
  EXPECT_EQ(r.links()[3].recognised_ends, 0) << "where the robot was when it was made is not in the old format";
  for (const Link& l : r.links()) EXPECT_EQ(l.scale, 1.0);
  // Format 6 had no gates: its links have none (the back end as it was when the map was made).
  const std::vector<uint8_t> v6 = testing::map_as_format_6(now);
  ExperienceMap r6;
  pos = 0;
  r6.deserialise(v6, pos, 6, 4);
  EXPECT_EQ(pos, v6.size());
  ASSERT_EQ(r6.links().size(), 4u);
  EXPECT_EQ(r6.links()[2].recognised_ends, 1);
  for (const Link& l : r6.links()) EXPECT_EQ(l.gate_m, std::numeric_limits<double>::infinity());
  // Today's format keeps each link's gate: the re-localisation's is the drift budget it was made within.
  ExperienceMap r7;
  pos = 0;
  r7.deserialise(now, pos, VitaSlam::kCheckpointFormat, 4);
  EXPECT_EQ(r7.links()[2].gate_m, m.links()[2].gate_m);
  EXPECT_LT(m.links()[2].gate_m, 1.0);
  EXPECT_EQ(m.links()[0].gate_m, std::numeric_limits<double>::infinity()) << "odometry between places is not gated";
}

TEST(ExperienceMap, ARetiredExperienceIsNeverACandidateAndStaysRetiredInACheckpoint) {
  const PoseCells cells{PoseCellParams{}};
  ExperienceMapParams p;
  p.drift_per_m = 1.0;
  ExperienceMap m(p);
  m.on_cycle({.template_id = 0, .visual_template_id = 0, .utime = 1000}, cells);  // experience 0, template 0
  m.integrate(0.1, 0.0, 0.0, 1.0);
  m.on_cycle({.template_id = 1, .visual_template_id = 1, .utime = 2000}, cells);  // experience 1, template 1
  ASSERT_EQ(m.experiences_of(1), std::vector<int>{1});
  EXPECT_TRUE(m.mapped_near({0.1, 0.0, 0.0}, 0.05, 0.5, m.size()));
  m.retire(1, 2);
  EXPECT_TRUE(m.experiences()[1].retired);
  EXPECT_TRUE(m.experiences_of(1).empty());
  EXPECT_FALSE(m.mapped_near({0.1, 0.0, 0.0}, 0.05, 0.5, m.size()));
  EXPECT_EQ(m.links().size(), 1u);  // kept in the graph
  std::vector<uint8_t> blob;
  m.serialise(blob);
  ExperienceMap r(p);
  size_t pos = 0;
  r.deserialise(blob, pos, VitaSlam::kCheckpointFormat, 2);
  EXPECT_EQ(pos, blob.size());
  EXPECT_TRUE(r.experiences()[1].retired);
  EXPECT_TRUE(r.experiences_of(1).empty());
  // Template 1 recognised again: its only experience is retired, so this is a new place of it.
  m.integrate(0.05, 0.0, 0.0, 1.0);
  const Event e = m.on_cycle({.template_id = 1, .visual_template_id = 1, .utime = 3000}, cells);
  EXPECT_EQ(e.type, EventType::NewExperience);
  EXPECT_EQ(m.experiences_of(1), std::vector<int>{2});
}

// gate_refused (a suspected kidnap's evidence, localiser.h) is set only when the gate alone refused:
// no experience of the template within the budget, whatever its view shift, and one beyond it that
// the view-shift rule would have taken.
TEST(ExperienceMap, ARecognitionIsGateRefusedOnlyWhenTheGateAloneRefusedIt) {
  const PoseCells cells{PoseCellParams{}};
  ExperienceMapParams p;
  p.drift_base = 0.25;
  p.drift_per_m = 0.15;
  ExperienceMap m(p);
  m.on_cycle({.template_id = 0, .visual_template_id = 0, .utime = 1000}, cells);  // experience 0 of template 0 at the origin, shift 0
  m.integrate(1.0, 0.0, 0.0, 1.0);
  m.on_cycle({.template_id = 1, .visual_template_id = 1, .utime = 2000}, cells);  // experience 1 of template 1 at 1 m
  // Template 0 again 1 m from its only experience (budget 0.25 + 0.15 · 1 m): refused by the gate.
  m.integrate(0.05, 0.0, 0.0, 1.0);
  Event e = m.on_cycle({.template_id = 0, .visual_template_id = 0, .utime = 3000}, cells);
  EXPECT_EQ(e.type, EventType::NewExperience);
  EXPECT_TRUE(e.gate_refused);
  // Template 1 here, its experience 5 cm away but seen 10 columns turned: the same place from another
  // pose (a new experience by the view-shift rule), not a disagreement.
  m.integrate(0.05, 0.0, 0.0, 1.0);
  e = m.on_cycle({.template_id = 1, .visual_template_id = 1, .utime = 4000, .view_shift = 10}, cells);
  EXPECT_EQ(e.type, EventType::NewExperience);
  EXPECT_FALSE(e.gate_refused);
  // Template 0 1 m from its only experience but seen 10 columns turned from it: set aside by the
  // view-shift rule as well, so not the gate's refusal alone.
  ExperienceMap far(p);
  far.on_cycle({.template_id = 0, .visual_template_id = 0, .utime = 1000}, cells);
  far.integrate(1.0, 0.0, 0.0, 1.0);
  e = far.on_cycle({.template_id = 0, .visual_template_id = 0, .utime = 2000, .view_shift = 10}, cells);
  EXPECT_EQ(e.type, EventType::NewExperience);
  EXPECT_FALSE(e.gate_refused);
}

TEST(ExperienceMap, SerialisationRoundTripsExactly) {
  const PoseCells cells{PoseCellParams{}};
  ExperienceMap m;
  m.on_cycle({.template_id = 0, .visual_template_id = 0, .tactile_template_id = 0, .dense = true, .pc_x = 10, .pc_y = 10, .utime = 1}, cells);
  m.integrate(0.3, 0.1, 0.2, 1.0);
  m.on_cycle({.template_id = 1, .visual_template_id = 1, .tactile_template_id = 1, .pc_x = 13, .pc_y = 11, .pc_theta = 2, .utime = 2}, cells);
  m.integrate(0.05, 0.0, 0.0, 1.0);
  std::vector<uint8_t> a, b;
  m.serialise(a);
  ExperienceMap r;
  size_t pos = 0;
  r.deserialise(a, pos, VitaSlam::kCheckpointFormat, 2);
  EXPECT_EQ(pos, a.size());
  r.serialise(b);
  EXPECT_EQ(a, b);
  EXPECT_EQ(r.current_id(), 1);
  EXPECT_EQ(r.offset(), m.offset());
  EXPECT_GT(m.travel_since_relocalisation(), 0.3);
  EXPECT_EQ(r.travel_since_relocalisation(), m.travel_since_relocalisation());
  // A template id beyond the store (it sized an index by it: 6 GB for 2^28), a heading that is not a
  // unit vector (its NaN spread through relaxation), a non-finite position: refused by name.
  auto patched = [&](std::size_t at, auto value) {
    std::vector<uint8_t> x = a;
    std::memcpy(x.data() + at, &value, sizeof value);
    return x;
  };
  constexpr std::size_t kFirst = 8, kTemplateId = kFirst + 7 * 8 + 8;
  // Two experiences of 7 f64, i64, 3 i32, u8, i32, u8; the link count; the first link's ends.
  constexpr std::size_t kLinkDx = kFirst + 2 * (7 * 8 + 8 + 3 * 4 + 1 + 4 + 1) + 8 + 2 * 4;
  for (const auto& [what, blob] : {std::pair{"template", patched(kTemplateId, int32_t{1 << 27})},
                                   std::pair{"template 2 of 2", patched(kTemplateId, int32_t{2})},
                                   std::pair{"visual template 5 of 2", patched(kTemplateId + 4, int32_t{5})},
                                   std::pair{"tactile template -7 of 2", patched(kTemplateId + 8, int32_t{-7})},
                                   std::pair{"heading", patched(kFirst + 2 * 8, 0.0)},
                                   std::pair{"pose", patched(kFirst, std::nan(""))},
                                   std::pair{"beyond 10000000 m", patched(kFirst, 1e300)},
                                   std::pair{"longer than 10000000 m", patched(kLinkDx, 1e300)}}) {
    ExperienceMap x;
    pos = 0;
    try {
      x.deserialise(blob, pos, VitaSlam::kCheckpointFormat, 2);
      ADD_FAILURE() << what;
    } catch (const std::runtime_error& e) {
      EXPECT_NE(std::string(e.what()).find(what), std::string::npos) << e.what();
    }
  }
  a[7] = 0xff;  // corrupt the experience count (its most significant byte)
  pos = 0;
  ExperienceMap bad;
  EXPECT_THROW(bad.deserialise(a, pos, VitaSlam::kCheckpointFormat, 2), std::runtime_error);
}

}  // namespace
}  // namespace whiskeye::slam
