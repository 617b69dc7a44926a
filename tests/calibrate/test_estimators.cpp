// whiskeye-calibrate's estimators on simulated bring-up sessions of a robot with a drawn true
// calibration: what each recovers and within what (docs/bring-up.md, "How well"), and the bad input
// each refuses with a line naming what was wrong.

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "bringup_rig.h"
#include "whiskeye/calibrate/estimators.h"

using namespace whiskeye;
using namespace whiskeye::calibrate;
using namespace whiskeye::calibrate::test;
using ::testing::HasSubstr;

namespace {

// The estimate of `key` for whisker w; fails the test when there is none.
double estimate(const Result& r, int w, const std::string& key) {
  for (const Estimate& e : r.estimates) {
    if (e.whisker == w && e.key == key) return e.new_value;
  }
  ADD_FAILURE() << "no estimate of " << key << " for whisker " << w;
  return NAN;
}

std::string joined(const Problems& problems) {
  std::string all;
  for (const std::string& p : problems) all += p + "\n";
  return all;
}

sim::SessionParams session(sim::Session kind, uint64_t seed = 11) {
  sim::SessionParams p;
  p.session = kind;
  p.seed = seed;
  return p;
}

class Calibrate : public ::testing::TestWithParam<uint64_t> {
 protected:
  const sim::TrueCalibration truth = sim::draw_true_calibration(GetParam());
  const wp::WhiskerCalibration& true_of(int w) const { return truth.calibration[static_cast<std::size_t>(w)]; }
};

TEST_P(Calibrate, RestRecoversEveryOffsetWithinACount) {
  const Result r = estimate_rest(record(session(sim::Session::kRest), truth), wired_as(truth), RestLimits{});
  ASSERT_TRUE(r.problems.empty()) << joined(r.problems);
  ASSERT_EQ(r.estimates.size(), 48u);
  for (int w = 0; w < kNumWhiskers; ++w) {
    EXPECT_NEAR(estimate(r, w, "offset_x"), true_of(w).offset_x, 1.0) << w;
    EXPECT_NEAR(estimate(r, w, "offset_y"), true_of(w).offset_y, 1.0) << w;
  }
}

TEST_P(Calibrate, MapFindsTheSwappedWhiskersTheMirroredBoardAndTheRotations) {
  const Result r = map_whiskers(find_pushes(record(session(sim::Session::kTaps), truth)), {}, defaults());
  ASSERT_TRUE(r.problems.empty()) << joined(r.problems);
  for (int w = 0; w < kNumWhiskers; ++w) {
    EXPECT_EQ(estimate(r, w, "channel"), truth.channel[static_cast<std::size_t>(w)]) << w;
    EXPECT_GT(estimate(r, w, "gain_x"), 0) << w;
    EXPECT_EQ(estimate(r, w, "gain_y") < 0, w / 4 == truth.mirrored_board) << w;
    // Taps of unknown size give the rotation only as well as the two gains are alike (gain refines it).
    EXPECT_NEAR(estimate(r, w, "rotation"), true_of(w).rotation, 0.05) << w;
  }
}

TEST_P(Calibrate, GainRecoversGainsAndRotationFromTheJig) {
  const Result r = fit_gains(find_pushes(record(session(sim::Session::kJig), truth)), {}, 0.5, wired_as(truth));
  ASSERT_TRUE(r.problems.empty()) << joined(r.problems);
  for (int w = 0; w < kNumWhiskers; ++w) {
    EXPECT_NEAR(estimate(r, w, "gain_x") / true_of(w).gain_x, 1.0, 0.003) << w;
    EXPECT_NEAR(estimate(r, w, "gain_y") / true_of(w).gain_y, 1.0, 0.003) << w;
    EXPECT_NEAR(estimate(r, w, "rotation"), true_of(w).rotation, 0.003) << w;
  }
}

TEST_P(Calibrate, ThetaRecoversOffsetAndGainFromTheEndStops) {
  const Result r = fit_theta(record(session(sim::Session::kSweep), truth), 60.0 * kPi / 180.0, wired_as(truth));
  ASSERT_TRUE(r.problems.empty()) << joined(r.problems);
  for (int w = 0; w < kNumWhiskers; ++w) {
    EXPECT_NEAR(estimate(r, w, "theta_offset"), true_of(w).theta_offset, 1.0) << w;
    EXPECT_NEAR(estimate(r, w, "theta_gain") / true_of(w).theta_gain, 1.0, 0.002) << w;
  }
}

INSTANTIATE_TEST_SUITE_P(TrueCalibrations, Calibrate, ::testing::Values(1, 2, 3, 4));

TEST(CalibrateRest, WorksOnClassicCanToo) {
  const sim::TrueCalibration truth = sim::draw_true_calibration(5);
  sim::SessionParams p = session(sim::Session::kRest);
  p.rate_hz = 100;
  const Result r = estimate_rest(record(p, truth, wp::BusMode::kClassic), wired_as(truth), RestLimits{});
  ASSERT_TRUE(r.problems.empty()) << joined(r.problems);
  EXPECT_NEAR(estimate(r, 7, "offset_x"), truth.calibration[7].offset_x, 1.0);
}

TEST(CalibrateRest, ASilentBoardIsOneLineNamingIt) {
  const sim::TrueCalibration truth = sim::draw_true_calibration(1);
  sim::SessionParams p = session(sim::Session::kRest);
  p.silent_board = 4;
  const Result r = estimate_rest(record(p, truth), wired_as(truth), RestLimits{});
  ASSERT_EQ(r.problems.size(), 1u) << joined(r.problems);
  EXPECT_THAT(r.problems[0], HasSubstr("board 4 (CAN node 5) sent no samples"));
}

// One sample per board gave 24 offsets ±0: no noise can be measured from it, nor a stuck sensor told.
TEST(CalibrateRest, ARecordingTooShortToEstimateTheNoiseIsRefusedPerBoard) {
  const sim::TrueCalibration truth = sim::draw_true_calibration(1);
  sim::SessionParams p = session(sim::Session::kRest);
  p.rest_s = 0.002;  // one sample at 500 Hz
  const Recording rec = record(p, truth);
  ASSERT_GE(rec.board(0).samples, 1);
  ASSERT_LT(rec.board(0).samples, 5);
  const Result r = estimate_rest(rec, wired_as(truth), RestLimits{});
  EXPECT_TRUE(r.estimates.empty());
  ASSERT_EQ(r.problems.size(), std::size_t{wp::kNumBoards}) << joined(r.problems);
  EXPECT_THAT(r.problems[0], HasSubstr("board 0 (CAN node 1) sent " + std::to_string(rec.board(0).samples)));
  EXPECT_THAT(r.problems[0], HasSubstr("fewer than the 100 that estimate its channels' offsets and noise"));
  p.rest_s = 0.2;  // 100 samples: enough
  const Result enough = estimate_rest(record(p, truth), wired_as(truth), RestLimits{});
  EXPECT_TRUE(enough.problems.empty()) << joined(enough.problems);
  EXPECT_EQ(enough.estimates.size(), 48u);
}

TEST(CalibrateRest, AStuckSensorIsNamed) {
  const sim::TrueCalibration truth = sim::draw_true_calibration(1);
  sim::SessionParams p = session(sim::Session::kRest);
  p.stuck = {9};
  const Result r = estimate_rest(record(p, truth), wired_as(truth), RestLimits{});
  ASSERT_EQ(r.problems.size(), 1u) << joined(r.problems);
  EXPECT_THAT(r.problems[0], HasSubstr("whisker 9 (row 1, column 3)"));
  EXPECT_THAT(r.problems[0], HasSubstr("stuck"));
}

TEST(CalibrateGain, AJigOnWhiskersWhiskerdWiresElsewhereIsRefused) {
  const sim::TrueCalibration truth = sim::draw_true_calibration(1);
  // whiskerd still has the boards' default wiring: the two swapped whiskers are not where it thinks.
  const Result r = fit_gains(find_pushes(record(session(sim::Session::kJig), truth)), {}, 0.5, defaults());
  ASSERT_EQ(r.problems.size(), 2u) << joined(r.problems);
  EXPECT_THAT(r.problems[0], HasSubstr("run map first"));
}

TEST(CalibrateMap, PushesThatDoNotMatchExpectAreRefused) {
  const sim::TrueCalibration truth = sim::draw_true_calibration(1);
  sim::SessionParams p = session(sim::Session::kTaps);
  p.order = {0, 1, 2};
  const Result r = map_whiskers(find_pushes(record(p, truth)), {0, 1}, defaults());
  ASSERT_EQ(r.problems.size(), 1u) << joined(r.problems);
  EXPECT_THAT(r.problems[0], HasSubstr("found 6 pushes in the recording, expected 2 per whisker"));
}

TEST(CalibrateTheta, ASweepInterruptedByAFaultIsRefused) {
  const sim::TrueCalibration truth = sim::draw_true_calibration(1);
  sim::SessionParams p = session(sim::Session::kSweep);
  p.fault_at_s = 2.0;
  const Result r = fit_theta(record(p, truth), 60.0 * kPi / 180.0, wired_as(truth));
  ASSERT_EQ(r.problems.size(), 1u) << joined(r.problems);
  EXPECT_THAT(r.problems[0], HasSubstr("sweep interrupted by a fault: board 0 reports a fault from 2.00 s"));
  EXPECT_TRUE(r.estimates.empty());
}

TEST(CalibrateBus, AHealthyBusPassesAndASilentBoardFailsNamingIt) {
  const sim::TrueCalibration truth = sim::draw_true_calibration(1);
  sim::SessionParams p = session(sim::Session::kRest);
  p.rest_s = 2.0;
  const BusReport ok = check_bus(record(p, truth), 500.0, 2.0);
  EXPECT_TRUE(ok.ok) << format_bus_report(ok);
  EXPECT_GT(ok.load, 0.25);
  EXPECT_LT(ok.load, ok.expected_load);
  p.silent_board = 2;
  const BusReport bad = check_bus(record(p, truth), 500.0, 2.0);
  EXPECT_FALSE(bad.ok);
  EXPECT_THAT(bad.boards[2].reason, HasSubstr("absent"));
  EXPECT_TRUE(bad.boards[1].ok);
  EXPECT_THAT(format_bus_report(bad), HasSubstr("    2     3        0.0           0.0     0  FAIL: absent"));
}

TEST(CalibrateBus, ASlowBoardFailsNamingItsRate) {
  const sim::TrueCalibration truth = sim::draw_true_calibration(1);
  sim::SessionParams p = session(sim::Session::kRest);
  p.rest_s = 2.0;
  const BusReport rep = check_bus(record(p, truth), 1000.0, 2.0);  // configured for 1 kHz, boards send 500 Hz
  EXPECT_FALSE(rep.ok);
  EXPECT_THAT(rep.boards[0].reason, HasSubstr("sample rate 500.0 Hz, configured 1000 Hz"));
}

TEST(CalibrateBounds, AnImplausibleValueIsRefusedNamingTheWhiskerAndTheKey) {
  const Problems p = check_bounds({{3, "offset_x", 0, 700, 0.1}, {4, "gain_y", 0, -0.0005, 0}, {5, "theta_gain", 0, 0.003, 0}});
  ASSERT_EQ(p.size(), 2u);
  EXPECT_THAT(p[0], HasSubstr("whisker 3 (row 0, column 3): offset_x = 700 is outside the plausible ±512 counts"));
  EXPECT_THAT(p[1], HasSubstr("whisker 5 (row 0, column 5): theta_gain = 0.003"));
}

TEST(CalibrateOutput, TheDropinHoldsEveryEstimatedKeyOncePerWhisker) {
  const auto entries = dropin_entries({{3, "offset_x", 0, 1.5, 0}, {1, "offset_x", 0, 2.5, 0}, {3, "offset_y", 0, -1, 0}});
  ASSERT_EQ(entries.size(), 2u);
  EXPECT_EQ(entries[0].index, 1);
  EXPECT_EQ(entries[1].index, 3);
  EXPECT_EQ(entries[1].keys.size(), 2u);
}

}  // namespace
