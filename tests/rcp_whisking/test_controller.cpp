// Controller: smooth start and stop, the WhiskEye RCP law, reaction in the same step, ceiling reset
// at each cycle start, cycle emission, the rate-limited variant, bad input.
#include <gtest/gtest.h>
#include <whiskeye/rcp/controller.h>

#include <cmath>

#include "helpers.h"

using namespace whiskeye;
using namespace whiskeye::rcp;
using whiskeye::rcp::test::kPeriodUs;
using whiskeye::rcp::test::make_sample;

namespace {

// Free whisking with small noise-free deflection; returns the last output.
ControlOutput run_free(Controller& c, int64_t from_seq, int64_t to_seq) {
  ControlOutput out;
  for (int64_t seq = from_seq; seq < to_seq; ++seq) out = c.step(make_sample(seq, 0.002, 0.0));
  return out;
}

double max_step(const PerWhisker<double>& a, const PerWhisker<double>& b) {
  double m = 0.0;
  for (int w = 0; w < kNumWhiskers; ++w) m = std::max(m, std::abs(a[w] - b[w]));
  return m;
}

}  // namespace

TEST(Controller, RestsAtThetaRestUntilEnabled) {
  ControllerParams p;
  Controller c{p};
  const ControlOutput out = run_free(c, 0, 100);
  EXPECT_EQ(out.phase, Phase::Rest);
  EXPECT_FALSE(out.enabled);
  EXPECT_EQ(out.cycle, 0);
  for (double t : out.theta_command) EXPECT_DOUBLE_EQ(t, p.pattern.theta_rest);
}

TEST(Controller, StartsSmoothlyAndReachesFullAmplitude) {
  ControllerParams p;
  Controller c{p};
  ControlOutput prev = run_free(c, 0, 10);
  c.enable();
  double peak = -10.0;
  const double limit = p.pattern.max_rate * kPeriodUs * 1e-6 + 1e-12;
  for (int64_t seq = 10; seq < 10 + 1500; ++seq) {
    const ControlOutput out = c.step(make_sample(seq, 0.002, 0.0));
    EXPECT_LE(max_step(out.theta_command, prev.theta_command), limit) << seq;
    // The ramped pattern itself starts without a step either (no slew limiter needed for that).
    EXPECT_LE(max_step(out.theta_nominal, prev.theta_nominal), 0.02) << seq;
    if (seq >= 10 + 500) peak = std::max(peak, out.theta_command[0]);
    prev = out;
  }
  EXPECT_NEAR(peak, p.pattern.theta_max, 1e-6);
}

TEST(Controller, CycleStartsAtEnableAndCountsOncePerPeriod) {
  Controller c{ControllerParams{}};
  c.enable();
  ControlOutput out = c.step(make_sample(0));
  EXPECT_EQ(out.cycle, 1);
  EXPECT_EQ(out.phase, Phase::Protract);
  EXPECT_DOUBLE_EQ(out.cycle_phase, 0.0);
  int emitted = 0;
  for (int64_t seq = 1; seq <= 5000; ++seq) {
    out = c.step(make_sample(seq));
    EXPECT_EQ(out.cycle, seq / 500 + 1);
    EXPECT_EQ(out.phase, (seq % 500) < 250 ? Phase::Protract : Phase::Retract) << seq;
    if (out.completed_cycle) {
      ++emitted;
      EXPECT_EQ(seq % 500, 0);
      EXPECT_EQ(out.completed_cycle->cycle, seq / 500);
      EXPECT_EQ(out.completed_cycle->samples.size(), 500u);
      EXPECT_EQ(out.completed_cycle->num_missing, 0);
    }
  }
  EXPECT_EQ(emitted, 10);
  EXPECT_EQ(c.stats().cycles_emitted, 10);
}

TEST(Controller, ReactsInTheSameStepAsTheFirstSampleAboveThreshold) {
  ControllerParams p;
  Controller c{p};
  c.enable();
  run_free(c, 0, 1200);  // learned by now; mid-protraction of cycle 3 at seq 1100..1250
  ASSERT_TRUE(c.detector().learned());
  const double threshold = c.detector().threshold()[7];
  // One sample just above threshold on whisker 7 only.
  WhiskerSample s = make_sample(1200, 0.002, 0.0);
  s.deflection_x[7] = -(threshold + 0.001);
  const ControlOutput before = c.last_output();
  const ControlOutput out = c.step(s);
  ASSERT_TRUE(out.in_contact[7]);
  EXPECT_EQ(out.phase, Phase::Protract);
  // Protraction ceased: the command no longer rises, and it is below the pattern in this very step.
  EXPECT_LE(out.theta_command[7], before.theta_command[7]);
  EXPECT_LT(out.theta_command[7], out.theta_nominal[7] - 1e-3);
  // The other whiskers keep whisking.
  EXPECT_DOUBLE_EQ(out.theta_command[8], out.theta_nominal[8]);
  EXPECT_GT(out.theta_command[8], before.theta_command[8]);
}

TEST(Controller, CeilingFollowsTheWhiskEyeLaw) {
  ControllerParams p;
  p.rcp.freeze_on_contact = false;  // the law alone
  Controller c{p};
  c.enable();
  run_free(c, 0, 1100);
  const double th = c.detector().threshold()[0];
  ControlOutput out;
  double m = 0.0;
  // Deflection rising then falling within protraction: the ceiling follows the running max of c.
  const double levels[] = {0.05, 0.1, 0.2, 0.15, 0.0};
  int64_t seq = 1100;
  for (double level : levels) {
    WhiskerSample s = make_sample(seq++, 0.0, 0.0);
    s.deflection_y[0] = th + level / p.detector.contact_gain;
    out = c.step(s);
    m = std::max(m, level);
    EXPECT_NEAR(out.contact[0], level, 1e-9);
    EXPECT_NEAR(out.theta_ceiling[0], p.pattern.theta_max + m * (p.rcp.theta_rcp - p.pattern.theta_max), 1e-9);
  }
}

TEST(Controller, CeilingsResetAtEachCycleStart) {
  ControllerParams p;
  Controller c{p};
  c.enable();
  run_free(c, 0, 1100);
  WhiskerSample s = make_sample(1100, 0.002, 0.0);
  s.deflection_x[3] = -0.5;  // strong contact: c = 1 -> ceiling theta_rcp
  ControlOutput out = c.step(s);
  EXPECT_NEAR(out.theta_ceiling[3], p.rcp.theta_rcp, 1e-9);
  out = run_free(c, 1101, 1500);  // rest of cycle 3
  EXPECT_EQ(out.cycle, 3);
  EXPECT_NEAR(out.theta_ceiling[3], p.rcp.theta_rcp, 1e-9);
  EXPECT_LT(out.theta_command[3], p.pattern.theta_min);
  out = c.step(make_sample(1500, 0.002, 0.0));
  EXPECT_EQ(out.cycle, 4);
  EXPECT_DOUBLE_EQ(out.theta_ceiling[3], p.pattern.theta_max);
  // And the command climbs back to the pattern without a step.
  ControlOutput prev = out;
  for (int64_t seq = 1501; seq < 1750; ++seq) {
    out = c.step(make_sample(seq, 0.002, 0.0));
    EXPECT_LE(max_step(out.theta_command, prev.theta_command), p.pattern.max_rate * 0.002 + 1e-12);
    prev = out;
  }
  EXPECT_NEAR(out.theta_command[3], out.theta_nominal[3], 1e-9);
}

TEST(Controller, ContactDuringRetractionDoesNotLowerTheCeiling) {
  ControllerParams p;
  Controller c{p};
  c.enable();
  run_free(c, 0, 1300);  // cycle 3, retraction from seq 1250
  WhiskerSample s = make_sample(1300, 0.002, 0.0);
  s.deflection_x[3] = -0.5;
  const ControlOutput out = c.step(s);
  EXPECT_TRUE(out.in_contact[3]);
  EXPECT_EQ(out.phase, Phase::Retract);
  EXPECT_DOUBLE_EQ(out.theta_ceiling[3], p.pattern.theta_max);
}

TEST(Controller, RateLimitedLawWithdrawsAtTheConfiguredRate) {
  ControllerParams p;
  p.rcp.law = RcpLaw::RateLimited;
  p.rcp.rate_limit = 2.0;
  Controller c{p};
  c.enable();
  run_free(c, 0, 1100);
  const double th = c.detector().threshold()[9];
  double prev_ceiling = 0.0;
  for (int64_t seq = 1100; seq < 1120; ++seq) {
    WhiskerSample s = make_sample(seq, 0.002, 0.0);
    s.deflection_x[9] = -(th + 1.0);  // c = 1
    const ControlOutput out = c.step(s);
    if (seq > 1100) {
      EXPECT_NEAR(prev_ceiling - out.theta_ceiling[9], 2.0 * 0.002, 1e-9);
    }
    prev_ceiling = out.theta_ceiling[9];
  }
}

TEST(Controller, OffLawOnlyReportsContacts) {
  ControllerParams p;
  p.rcp.law = RcpLaw::Off;
  Controller c{p};
  c.enable();
  run_free(c, 0, 1100);
  WhiskerSample s = make_sample(1100, 0.002, 0.0);
  s.deflection_x[3] = -0.5;
  const ControlOutput out = c.step(s);
  EXPECT_TRUE(out.in_contact[3]);
  EXPECT_DOUBLE_EQ(out.theta_command[3], out.theta_nominal[3]);
}

TEST(Controller, DisableMidCycleRetractsSmoothlyToRest) {
  ControllerParams p;
  Controller c{p};
  c.enable();
  ControlOutput prev = run_free(c, 0, 1240);  // near peak protraction of cycle 3
  ASSERT_GT(prev.theta_command[0], deg_to_rad(40.0));
  c.disable();
  const int64_t emitted_before = c.stats().cycles_emitted;
  const double limit = p.pattern.max_rate * 0.002 + 1e-12;
  int64_t rest_seq = -1;
  for (int64_t seq = 1240; seq < 1240 + 1000; ++seq) {
    const ControlOutput out = c.step(make_sample(seq, 0.002, 0.0));
    EXPECT_LE(max_step(out.theta_command, prev.theta_command), limit) << seq;
    // The pattern with its amplitude ramp is itself smooth: no step larger than the slew limit.
    EXPECT_LE(max_step(out.theta_nominal, prev.theta_nominal), limit) << seq;
    EXPECT_FALSE(out.enabled);
    if (out.phase == Phase::Rest && rest_seq < 0) rest_seq = seq;
    prev = out;
  }
  ASSERT_GT(rest_seq, 0);
  // Ramp time 0.5 s = 250 periods.
  EXPECT_LE(rest_seq - 1240, 251);
  for (double t : prev.theta_command) EXPECT_NEAR(t, p.pattern.theta_rest, 1e-12);
  EXPECT_EQ(c.stats().cycles_emitted, emitted_before);  // the interrupted cycle is not emitted
  EXPECT_EQ(c.stats().cycles_discarded, 1);
}

TEST(Controller, IsAtRestOnlyOnceTheSlewLimitedCommandIsBackAtRest) {
  ControllerParams p;
  p.pattern.ramp_time = 0.0;  // the amplitude drops at once; the command may not
  Controller c{p};
  EXPECT_TRUE(c.at_rest());
  c.enable();
  run_free(c, 0, 1240);  // near peak protraction
  EXPECT_FALSE(c.at_rest());
  c.disable();
  int64_t seq = 1240;
  c.step(make_sample(seq++, 0.002, 0.0));
  EXPECT_FALSE(c.running()) << "ramp_time 0: the pattern stops in one step";
  EXPECT_FALSE(c.at_rest()) << "but the command is still tens of degrees out";
  int periods = 1;
  while (!c.at_rest() && periods < 1000) {
    c.step(make_sample(seq++, 0.002, 0.0));
    ++periods;
  }
  EXPECT_TRUE(c.at_rest());
  EXPECT_GT(periods, 10) << "slewed back at max_rate, not in one step";
  for (double t : c.last_output().theta_command) EXPECT_NEAR(t, p.pattern.theta_rest, 1e-9);
}

TEST(Controller, ALateSampleDoesNotLicenseAStep) {
  ControllerParams p;
  Controller c{p};
  c.enable();
  const ControlOutput before = run_free(c, 0, 1200);
  // 200 ms without a sample (the loop stalled): the next command moves by at most two periods' slew.
  const ControlOutput after = c.step(make_sample(1300, 0.002, 0.0));
  EXPECT_LE(max_step(after.theta_command, before.theta_command), p.pattern.max_rate * 2 * 0.002 + 1e-12);
}

TEST(Controller, ReenableStartsANewCycleAtThetaMin) {
  ControllerParams p;
  Controller c{p};
  c.enable();
  run_free(c, 0, 1240);
  c.disable();
  ControlOutput out = run_free(c, 1240, 1600);
  ASSERT_EQ(out.phase, Phase::Rest);
  const int64_t cycle = out.cycle;
  c.enable();
  out = c.step(make_sample(1600));
  EXPECT_EQ(out.cycle, cycle + 1);
  EXPECT_EQ(out.phase, Phase::Protract);
  EXPECT_DOUBLE_EQ(out.cycle_phase, 0.0);
  ControlOutput done;
  for (int64_t seq = 1601; seq <= 2100; ++seq) {
    out = c.step(make_sample(seq));
    if (out.completed_cycle) done = out;
  }
  ASSERT_TRUE(done.completed_cycle.has_value());
  EXPECT_EQ(done.completed_cycle->cycle, cycle + 1);
  EXPECT_EQ(done.completed_cycle->samples.size(), 500u);
}

TEST(Controller, SequenceGapsAreMarkedInTheEmittedCycle) {
  Controller c{ControllerParams{}};
  c.enable();
  ControlOutput done;
  for (int64_t seq = 0; seq <= 1000; ++seq) {
    if (seq == 600 || seq == 601 || seq == 999) continue;
    const ControlOutput out = c.step(make_sample(seq));
    if (out.completed_cycle && out.completed_cycle->cycle == 2) done = out;
  }
  ASSERT_TRUE(done.completed_cycle.has_value());
  EXPECT_EQ(done.completed_cycle->samples.size(), 500u);
  EXPECT_EQ(done.completed_cycle->num_missing, 3);
  EXPECT_FALSE(done.completed_cycle->samples[100].valid);
  EXPECT_FALSE(done.completed_cycle->samples[499].valid);
  EXPECT_EQ(c.stats().missing_samples, 3);
}

TEST(Controller, IgnoresSamplesWhoseTimeDoesNotAdvance) {
  Controller c{ControllerParams{}};
  c.enable();
  run_free(c, 0, 100);
  const ControlOutput before = c.last_output();
  WhiskerSample stale = make_sample(50);
  stale.deflection_x.fill(0.9);
  const ControlOutput out = c.step(stale);
  EXPECT_EQ(out.utime, before.utime);
  EXPECT_EQ(out.theta_command, before.theta_command);
  EXPECT_FALSE(out.in_contact[0]);
  EXPECT_EQ(c.stats().rejected_samples, 1);
}

TEST(Controller, RowPhaseLeadShiftsThatRowsCeilingReset) {
  ControllerParams p;
  p.pattern.row_phase = {0.0, 0.5, 0.0, 0.0};
  Controller c{p};
  c.enable();
  run_free(c, 0, 1300);  // master in retraction of cycle 3; row 1 protracting (own phase 0.1)
  WhiskerSample s = make_sample(1300, 0.002, 0.0);
  s.deflection_x[whisker_index(1, 2)] = -0.5;
  s.deflection_x[whisker_index(0, 2)] = -0.5;
  ControlOutput out = c.step(s);
  EXPECT_NEAR(out.theta_ceiling[whisker_index(1, 2)], p.rcp.theta_rcp, 1e-9);
  EXPECT_DOUBLE_EQ(out.theta_ceiling[whisker_index(0, 2)], p.pattern.theta_max);  // row 0 retracting
  // Row 1's own cycle restarts at master phase 0.5 (seq 1750), not at the master cycle start.
  out = run_free(c, 1301, 1500);
  EXPECT_NEAR(out.theta_ceiling[whisker_index(1, 2)], p.rcp.theta_rcp, 1e-9);
  out = run_free(c, 1500, 1751);
  EXPECT_DOUBLE_EQ(out.theta_ceiling[whisker_index(1, 2)], p.pattern.theta_max);
}
