// whiskerd's control core without a bus: frames in, one period out; the safety state machine and
// the motor lines that follow it (WhiskerCore, LineGuard: whiskerd_core.h).
#include <gtest/gtest.h>

#include <whiskeye/driver_status_t.hpp>
#include <whiskeye/rcp_state_t.hpp>
#include <whiskeye/whisk_cycle_t.hpp>
#include <whiskeye/whisker_sample_t.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <set>
#include <string>
#include <vector>

#include "whiskeye/whiskerd/config.h"
#include "whiskeye/whiskerd/lcm.h"
#include "whiskeye/whiskerd/whiskerd_core.h"
#include "whiskerd_rig.h"

using namespace whiskeye;
using namespace whiskeye::whiskerd;
using namespace whiskeye::whiskerd::test;

TEST(WhiskerdCore, WaitsForEveryBoardBeforeEnablingMotors) {
  Rig rig;
  rig.feed(0, 20, /*skip_board=*/5);
  rig.step();
  EXPECT_EQ(rig.core.safety(), Safety::kWaiting);
  EXPECT_FALSE(rig.core.motors_enabled());
  EXPECT_EQ(rig.out.command.enable_mask, 0u);
  EXPECT_EQ(rig.out.status[20], int8_t{whisker_sample_t::STATUS_STALE});
  rig.seq = 1;
  rig.run(1);
  EXPECT_EQ(rig.core.safety(), Safety::kRunning);
  EXPECT_EQ(rig.out.command.enable_mask, 0xFFFFFFu);
}

TEST(WhiskerdCore, CalibratesDecodedValuesIntoThePeriodOutput) {
  Params p = test_params();
  p.calibration[7].offset_x = 7;
  p.calibration[7].gain_x = 0.5;
  Rig rig(p);
  rig.run(1);
  EXPECT_EQ(rig.out.raw_theta[9], 90);
  EXPECT_NEAR(rig.out.theta[9], 90 * wp::kThetaRadPerCount, 1e-6);
  EXPECT_NEAR(rig.out.deflection_y[9], -9.0 / 2047, 1e-6);
  EXPECT_NEAR(rig.out.deflection_x[7], 0.0, 1e-6);
  EXPECT_EQ(rig.out.status[9], 0);
}

TEST(WhiskerdCore, AWhiskerWiredToAnotherChannelReadsAndDrivesThatChannel) {
  // Whiskers 5 and 6 swapped at board 1: whisker 5's sensor and motor are on channel 6 and back.
  Params p = test_params();
  p.channel[5] = 6;
  p.channel[6] = 5;
  p.calibration[5].theta_offset = 100;  // tells the two whiskers' targets apart
  Rig rig(p);
  rig.run(5, 33);  // channel 5 reads x = 33, channel 6 reads x = 6
  EXPECT_EQ(rig.out.raw_x[6], 33);
  EXPECT_EQ(rig.out.raw_x[5], 6);
  EXPECT_NEAR(rig.out.deflection_x[6], 33.0 / 2047, 1e-6);
  EXPECT_EQ(rig.out.raw_theta[5], 60);
  // Targets go out by channel: whisker 5's (offset 100 counts) on channel 6.
  EXPECT_EQ(rig.out.command.theta_target[6], wp::theta_to_counts(rig.out.theta_command[5], p.calibration[5]));
  EXPECT_EQ(rig.out.command.theta_target[5], wp::theta_to_counts(rig.out.theta_command[6], p.calibration[6]));
  EXPECT_NE(rig.out.command.theta_target[6], rig.out.command.theta_target[5]);
  EXPECT_EQ(rig.out.command.enable_mask, 0xFFFFFFu);
}

TEST(WhiskerdCore, RefusesChannelsThatAreNotAPermutation) {
  Params p = test_params();
  p.channel[5] = 6;
  EXPECT_THROW(WhiskerCore core(p), std::invalid_argument);
}

TEST(WhiskerdCore, RepeatedSampleIsMarkedStale) {
  Rig rig;
  rig.run(3);
  rig.step();  // no new frames this period
  for (int w = 0; w < 24; ++w) EXPECT_EQ(rig.out.status[w], int8_t{whisker_sample_t::STATUS_STALE}) << w;
}

TEST(WhiskerdCore, CountsRejectedFramesByReasonAndGapsPerBoard) {
  Rig rig;
  std::array<uint8_t, 32> buf{};
  rig.core.on_frame(0x181, true, std::span(buf.data(), 8), 0);
  rig.core.on_frame(0x187, true, buf, 0);
  rig.run(2);
  rig.seq += 3;
  rig.run(1);
  auto& c = rig.core.counters();
  EXPECT_EQ(c[Counters::kRejectedWrongLength], 1);
  EXPECT_EQ(c[Counters::kRejectedUnknownId], 1);
  EXPECT_EQ(c[Counters::kGapsBoard0 + 4], 3);
  EXPECT_EQ(c[Counters::kGaps], 3 * wp::kNumBoards);
}

// Counters say how many; the log must say what was wrong: the 1st, 10th, 100th rejected frame is
// kept as a line naming the reason and the id, taken once by the control loop.
TEST(WhiskerdCore, RejectedFramesAreNamedForTheLogAtThe1st10th100th) {
  Rig rig;
  std::array<uint8_t, 32> buf{};
  EXPECT_EQ(rig.core.take_rejection_line(), nullptr);
  rig.core.on_frame(0x181, true, std::span(buf.data(), 24), 0);
  const char* first = rig.core.take_rejection_line();
  ASSERT_NE(first, nullptr);
  EXPECT_STREQ(first, wp::reject_text(wp::decode_frame(0x181, true, std::span(buf.data(), 24), wp::BusMode::kFd, {}))
                          .c_str());
  EXPECT_NE(std::string(first).find("(24 bytes, expected 32), id 0x181"), std::string::npos) << first;
  EXPECT_EQ(rig.core.take_rejection_line(), nullptr) << "taken once";
  std::vector<int64_t> logged_at;
  for (int i = 2; i <= 150; ++i) {
    rig.core.on_frame(0x187, true, buf, 0);
    if (const char* line = rig.core.take_rejection_line()) {
      logged_at.push_back(rig.core.rejected_frames());
      EXPECT_NE(std::string(line).find("id 0x187"), std::string::npos) << line;
    }
  }
  EXPECT_EQ(logged_at, (std::vector<int64_t>{10, 100}));
  EXPECT_EQ(rig.core.rejected_frames(), 150);
}

TEST(WhiskerdCore, ABoardsBootUpHeartbeatRestartsItsSequenceWithoutAPhantomGap) {
  // Board 2 reboots at seq 40000 (upper half of the u16 space, so its restart at 0 looks like a
  // forward step): its boot-up heartbeat keeps the 25535 samples it never sent out of gaps_board2.
  Rig rig;
  rig.seq = 39900;
  rig.run(101);
  ASSERT_EQ(rig.core.counters()[Counters::kGaps], 0);
  rig.heartbeat(2, wp::kNmtBootUp);
  for (int i = 0; i < 10; ++i) {
    rig.feed(rig.seq++, 20, /*skip_board=*/2);
    rig.send(2, i);
    rig.step();
  }
  EXPECT_EQ(rig.core.counters()[Counters::kGapsBoard0 + 2], 0);
  EXPECT_EQ(rig.core.counters()[Counters::kGaps], 0);
  EXPECT_EQ(rig.core.counters()[Counters::kBoardResyncs], 1);
  EXPECT_EQ(rig.core.counters()[Counters::kLateSamples], 0);
  for (int w = 8; w < 12; ++w) EXPECT_EQ(rig.out.status[w], 0) << w;  // board 2 fresh
}

TEST(WhiskerdCore, RebootedBoardIsFollowedAndCountedInDriverStatus) {
  Rig rig;
  rig.run(300);
  ASSERT_EQ(rig.core.safety(), Safety::kRunning);
  // Board 2 reboots: its sequence restarts at 0 while the other boards go on.
  for (int i = 0; i < 10; ++i) {
    rig.feed(rig.seq++, 20, /*skip_board=*/2);
    rig.send(2, i);
    rig.step();
  }
  EXPECT_EQ(rig.core.counters()[Counters::kBoardResyncs], 1);
  EXPECT_EQ(rig.core.safety(), Safety::kRunning);
  for (int w = 8; w < 12; ++w) EXPECT_EQ(rig.out.status[w], 0) << w;  // board 2 fresh again
  StatusSnapshot s;
  s.reason = "";
  s.bus_state = "error-active";
  s.counters = rig.core.counters().values;
  driver_status_t m;
  to_lcm(s, m);
  int64_t resyncs = -1;
  for (int i = 0; i < m.num_counters; ++i) {
    if (m.counter_names[i] == "board_resyncs") resyncs = m.counter_values[i];
  }
  EXPECT_EQ(resyncs, 1);
}

TEST(WhiskerdCore, CounterNamesMatchTheirIndices) {
  std::set<std::string> names;
  for (const char* n : Counters::kNames) {
    ASSERT_NE(n, nullptr);
    names.insert(n);
  }
  EXPECT_EQ(names.size(), std::size_t{Counters::kCount});
  EXPECT_STREQ(Counters::kNames[Counters::kLateSamples], "late_samples");
  EXPECT_STREQ(Counters::kNames[Counters::kBoardResyncs], "board_resyncs");
  for (int b = 0; b < wp::kNumBoards; ++b) {
    EXPECT_EQ(Counters::kNames[Counters::kGapsBoard0 + b], "gaps_board" + std::to_string(b));
  }
}

TEST(WhiskerdCore, AnOverTemperatureBoardHasItsMotorsOffUntilItCoolsDown) {
  Rig r;
  r.run(5);
  ASSERT_EQ(r.out.command.enable_mask, 0xffffffu);
  auto hot = [&](bool overtemp, bool board2_sends = true) {
    for (int b = 0; b < wp::kNumBoards; ++b) {
      if (b == 2 && !board2_sends) continue;
      wp::BoardSample s;
      s.board = b;
      s.seq = static_cast<uint16_t>(r.seq);
      if (b == 2 && overtemp) s.status = wp::kBoardOvertemp;
      std::array<uint8_t, 32> buf{};
      wp::encode_sample_fd(s, buf);
      r.core.on_frame(wp::sample_id({}, b), true, buf, r.mono);
    }
    ++r.seq;
    r.step();
  };
  for (int i = 0; i < 3; ++i) hot(true);
  EXPECT_EQ(r.out.command.enable_mask, 0xffffffu & ~(0xfu << 8)) << "board 2's whiskers 8..11 off";
  EXPECT_EQ(r.core.safety(), Safety::kRunning) << "the other boards go on whisking";
  EXPECT_EQ(r.out.status[9], whisker_sample_t::STATUS_OVERTEMP) << "motor off, the reading still valid";
  EXPECT_EQ(r.out.status[4], whisker_sample_t::STATUS_OK);
  EXPECT_EQ(r.core.counters()[Counters::kOvertempBoardPeriods], 3);
  hot(true, false);  // board 2 silent for a period: its last (hot) sample is not counted again
  EXPECT_EQ(r.core.counters()[Counters::kOvertempBoardPeriods], 3);
  EXPECT_EQ(r.out.status[9], whisker_sample_t::STATUS_OVERTEMP | whisker_sample_t::STATUS_STALE);
  hot(false);
  EXPECT_EQ(r.out.command.enable_mask, 0xffffffu) << "cooled down: back on";
}

TEST(WhiskerdCore, FaultDisablesMotorsAtOnceAndLatches) {
  Rig rig;
  rig.run(20);
  ASSERT_TRUE(rig.core.motors_enabled());
  rig.core.fault();
  EXPECT_FALSE(rig.core.motors_enabled());
  rig.run(1);
  EXPECT_EQ(rig.out.command.enable_mask, 0u);
  rig.run(200);
  EXPECT_EQ(rig.core.safety(), Safety::kFault);
  EXPECT_FALSE(rig.core.motors_enabled());
}

TEST(WhiskerdLines, EnableLineFollowsTheCoreAndAFaultEdgeDropsItBeforeTheNextStep) {
  gpio::FakeMotorLines lines;
  Rig rig;
  LineGuard guard(lines);
  EXPECT_FALSE(lines.enable);
  for (int i = 0; i < 10; ++i) {
    guard.poll_fault(rig.core);
    rig.run(1);
    guard.update(rig.core);
  }
  EXPECT_TRUE(lines.enable);
  // A pulse on the fault line that is already over when polled still counts.
  lines.fault_edge = true;
  EXPECT_TRUE(guard.poll_fault(rig.core));
  EXPECT_FALSE(lines.enable);  // dropped before the next step runs
  EXPECT_EQ(rig.core.safety(), Safety::kFault);
  const int writes = lines.enable_writes;
  for (int i = 0; i < 50; ++i) {
    EXPECT_FALSE(guard.poll_fault(rig.core));
    rig.run(1);
    guard.update(rig.core);
  }
  EXPECT_FALSE(lines.enable);
  EXPECT_EQ(lines.enable_writes, writes);  // latched: never re-enabled
}

TEST(WhiskerdLines, NoGpioLinesNeverReportAFault) {
  gpio::NoMotorLines lines;
  Rig rig;
  LineGuard guard(lines);
  rig.run(5);
  EXPECT_FALSE(guard.poll_fault(rig.core));
  guard.update(rig.core);
  EXPECT_TRUE(guard.enabled());
}

TEST(WhiskerdCore, StaleBusRetractsThenDropsEnableThenRecovers) {
  Rig rig;
  rig.run(300);
  ASSERT_EQ(rig.core.safety(), Safety::kRunning);
  int periods = 0;
  while (rig.core.safety() != Safety::kRetracting && periods < 100) {
    rig.step();
    ++periods;
  }
  ASSERT_EQ(rig.core.safety(), Safety::kRetracting);
  EXPECT_LE(periods * kPeriod, 0.02e6 + 2 * kPeriod);  // within the stale timeout
  EXPECT_TRUE(rig.core.motors_enabled());              // still driving the retraction
  for (int i = 0; i < 200 && rig.core.safety() == Safety::kRetracting; ++i) rig.step();
  EXPECT_EQ(rig.core.safety(), Safety::kDisabled);
  EXPECT_FALSE(rig.core.motors_enabled());
  EXPECT_NE(std::string(rig.core.reason()).find("stale"), std::string::npos);
  rig.run(3);
  EXPECT_EQ(rig.core.safety(), Safety::kRunning);
  EXPECT_TRUE(rig.core.motors_enabled());
}

TEST(WhiskerdCore, HeartbeatsAloneAreAStaleBus) {
  Rig rig;
  rig.run(300);
  ASSERT_EQ(rig.core.safety(), Safety::kRunning);
  for (int i = 0; i < 2500; ++i) {  // 5 s of heartbeats and nothing else
    rig.heartbeats();
    rig.step();
  }
  EXPECT_EQ(rig.core.safety(), Safety::kDisabled);
  EXPECT_FALSE(rig.core.motors_enabled());
  EXPECT_EQ(rig.out.command.enable_mask, 0u);
  EXPECT_NE(std::string(rig.core.reason()).find("stale bus"), std::string::npos) << rig.core.reason();
  StatusSnapshot s;
  s.safety = rig.core.safety();
  s.reason = rig.core.reason();
  s.bus_state = "error-active";
  driver_status_t m;
  to_lcm(s, m);
  EXPECT_NE(m.state, int8_t{driver_status_t::STATE_OK});
}

TEST(WhiskerdCore, SilentBoardRetractsNamingItThenRecoversWhenItStreamsAgain) {
  Rig rig;
  rig.run(300);
  ASSERT_EQ(rig.core.safety(), Safety::kRunning);
  auto period_without_board3 = [&] {
    rig.feed(rig.seq++, 20, /*skip_board=*/3);
    rig.step();
  };
  int periods = 0;
  while (rig.core.safety() != Safety::kRetracting && periods < 2500) {
    period_without_board3();
    ++periods;
  }
  ASSERT_EQ(rig.core.safety(), Safety::kRetracting);
  EXPECT_LE(periods * kPeriod, 0.02e6 + 2 * kPeriod);  // within the stale timeout
  EXPECT_NE(std::string(rig.core.reason()).find("board 3"), std::string::npos) << rig.core.reason();
  for (int i = 0; i < 200 && rig.core.safety() == Safety::kRetracting; ++i) period_without_board3();
  EXPECT_EQ(rig.core.safety(), Safety::kDisabled);
  EXPECT_FALSE(rig.core.motors_enabled());
  EXPECT_EQ(rig.out.command.enable_mask, 0u);
  EXPECT_NE(std::string(rig.core.reason()).find("board 3"), std::string::npos) << rig.core.reason();
  for (int i = 0; i < 100; ++i) period_without_board3();  // the other five are not enough
  EXPECT_EQ(rig.core.safety(), Safety::kDisabled);
  rig.run(3);
  EXPECT_EQ(rig.core.safety(), Safety::kRunning);
  EXPECT_EQ(rig.out.command.enable_mask, 0xFFFFFFu);
}

TEST(WhiskerdCore, OnlyFreshSamplesKeepABoardAlive) {
  Rig rig;
  rig.run(300);
  ASSERT_EQ(rig.core.safety(), Safety::kRunning);
  const int frozen = rig.seq - 1;
  for (int i = 0; i < 100 && rig.core.safety() == Safety::kRunning; ++i) {
    rig.feed(rig.seq++, 20, /*skip_board=*/1);
    rig.send(1, frozen);      // a duplicate of its last sample
    rig.send(1, frozen - 5);  // a late one
    std::array<uint8_t, 32> buf{};
    rig.core.on_frame(wp::sample_id({}, 1), true, std::span(buf.data(), 8), rig.mono);  // rejected
    rig.step();
  }
  EXPECT_EQ(rig.core.safety(), Safety::kRetracting);
  EXPECT_NE(std::string(rig.core.reason()).find("board 1"), std::string::npos) << rig.core.reason();
}

TEST(WhiskerdCore, StopRequestRetractsToRestThenFinishes) {
  Params p = test_params();
  p.retract_time_s = 2.0;  // longer than the controller's ramp: the ramp decides
  Rig rig(p);
  rig.run(300);
  rig.core.request_stop();
  int periods = 0;
  while (!rig.core.finished() && periods < 1000) {
    rig.run(1);
    ++periods;
  }
  EXPECT_TRUE(rig.core.finished());
  EXPECT_FALSE(rig.core.motors_enabled());
  EXPECT_EQ(rig.out.command.enable_mask, 0u);
  EXPECT_NEAR(rig.out.theta_command[0], test_params().controller.pattern.theta_rest, 0.05);
}

TEST(WhiskerdCore, EnableDropsOnlyOnceTheWhiskersAreBackAtRest) {
  Params p = test_params();
  p.retract_time_s = 2.0;
  p.controller.pattern.ramp_time = 0.0;  // the pattern stops at once; the slew-limited command not
  Rig rig(p);
  const double rest = p.controller.pattern.theta_rest;
  rig.run(300);
  while (std::abs(rig.out.theta_command[0] - rest) < 0.5) rig.run(1);  // well protracted
  rig.core.request_stop();
  int powered_periods = 0;
  for (int i = 0; i < 1000 && !rig.core.finished(); ++i) {
    rig.run(1);
    if (rig.out.command.enable_mask != 0) {
      ++powered_periods;
    } else {
      for (int w = 0; w < rcp::kNumWhiskers; ++w) {
        ASSERT_NEAR(rig.out.theta_command[w], rest, 1e-6) << "enable dropped with whisker " << w << " out";
      }
    }
  }
  EXPECT_TRUE(rig.core.finished());
  EXPECT_GT(powered_periods, 10) << "the motors drove the whiskers back";
}

TEST(WhiskerdCore, ContactLowersTheCeilingAndTheMotorTarget) {
  Rig rig;
  // Whisk until protraction, then touch whisker 5.
  rig.run(300);
  while (rig.out.phase != rcp_state_t::PHASE_PROTRACT || rig.out.cycle_phase < 0.1) rig.run(1);
  const float before = rig.out.theta_command[5];
  const int16_t target_before = rig.out.command.theta_target[5];
  rig.run(1, 1500);
  EXPECT_LT(rig.out.theta_ceiling[5], 0.0);
  EXPECT_LT(rig.out.theta_command[5], before);
  EXPECT_LT(rig.out.command.theta_target[5], target_before);
  EXPECT_GT(rig.out.theta_command[6], rig.out.theta_command[5]);  // neighbours keep whisking
}

TEST(WhiskerdCore, CompletedCycleIsHandedOutOnce) {
  Rig rig;
  int cycles = 0;
  for (int i = 0; i < 1300; ++i) {
    rig.run(1);
    if (rig.out.completed_cycle) {
      ++cycles;
      whisk_cycle_t msg;
      to_lcm(*rig.out.completed_cycle, msg);
      EXPECT_EQ(msg.num_samples, static_cast<int>(msg.sample_utime.size()));
      EXPECT_GT(msg.num_samples, 400);
    }
  }
  EXPECT_GE(cycles, 1);
}

TEST(WhiskerdCore, WallClockStepsNeitherStopNorJerkTheWhiskingAndCyclesStayInEpochTime) {
  Rig rig;
  rig.run(300);
  const double max_step = test_params().controller.pattern.max_rate * kPeriod * 1e-6;
  std::array<float, kN> prev = rig.out.theta_command;
  double max_change = 0.0;
  int64_t first_cycle = rig.out.cycle;
  int cycles_after_back = 0, cycles_after_forward = 0;
  constexpr int kBack = 200, kForward = 1500, kEnd = 3000;
  for (int i = 0; i < kEnd; ++i) {
    if (i == kBack) rig.utime -= 5'000'000;          // NTP steps the wall clock back 5 s
    if (i == kForward) rig.utime += 3'600'000'000;   // and forward 1 h; the monotonic clock is steady
    rig.run(1);
    for (int w = 0; w < kN; ++w) {
      max_change = std::max(max_change, static_cast<double>(std::abs(rig.out.theta_command[w] - prev[w])));
    }
    prev = rig.out.theta_command;
    if (const auto& c = rig.out.completed_cycle) {
      (i >= kForward ? cycles_after_forward : cycles_after_back) += i >= kBack;
      // Its last sample is the previous period's, in the completing period's epoch time.
      EXPECT_EQ(c->utime_end, rig.out.utime - kPeriod) << i;
      ASSERT_FALSE(c->samples.empty());
      EXPECT_EQ(c->utime_start, c->samples.front().utime);
      EXPECT_EQ(c->utime_end, c->samples.back().utime);
      for (std::size_t k = 1; k < c->samples.size(); ++k) {
        EXPECT_EQ(c->samples[k].utime - c->samples[k - 1].utime, kPeriod) << i << " " << k;
      }
    }
  }
  EXPECT_LE(max_change, max_step + 1e-5);
  EXPECT_EQ(rig.core.controller().stats().rejected_samples, 0);
  EXPECT_GE(cycles_after_back, 2);     // 2.6 s of whisking at 1 Hz between the steps
  EXPECT_GE(cycles_after_forward, 2);  // 3 s after
  EXPECT_GE(rig.out.cycle - first_cycle, 5);
  EXPECT_EQ(rig.core.safety(), Safety::kRunning);
}

TEST(WhiskerdCore, StatusMessageCarriesCountersAndLatencies) {
  StatusSnapshot s;
  s.safety = Safety::kRunning;
  s.reason = "";
  s.bus_state = "error-active";
  s.counters[Counters::kGapsBoard0 + 2] = 6;
  s.loop_time = {10, 20, 30, 500};
  driver_status_t m;
  to_lcm(s, m);
  EXPECT_EQ(m.state, int8_t{driver_status_t::STATE_OK});
  EXPECT_EQ(m.driver, "whiskerd");
  bool found = false;
  for (int i = 0; i < m.num_counters; ++i) {
    if (m.counter_names[i] == "gaps_board2") found = m.counter_values[i] == 6;
  }
  EXPECT_TRUE(found);
  EXPECT_EQ(m.num_stats, static_cast<int>(m.stat_values.size()));
  s.bus_state = "bus-off";
  to_lcm(s, m);
  EXPECT_EQ(m.state, int8_t{driver_status_t::STATE_DEGRADED});
  EXPECT_NE(m.message.find("bus-off"), std::string::npos);
}

TEST(WhiskerdCore, ClassicModeAssemblesPerWhiskerFramesAndRuns) {
  Params p = test_params();
  p.mode = wp::BusMode::kClassic;
  p.rate_hz = 100;
  WhiskerCore core(p);
  PeriodOutput out;
  int64_t mono = 1000000, utime = 1700000000000000;
  for (int seq = 0; seq < 3; ++seq) {
    for (int b = 0; b < wp::kNumBoards; ++b) {
      for (int k = 0; k < 4; ++k) {
        const int w = 4 * b + k;
        wp::WhiskerFragment f{b, static_cast<uint8_t>(seq), k, 0, {static_cast<int16_t>(w), 0, static_cast<int16_t>(w), false}};
        std::array<uint8_t, 8> buf{};
        wp::encode_fragment(f, buf);
        core.on_frame(wp::sample_id({}, b), false, buf, mono);
      }
    }
    mono += 10000;
    utime += 10000;
    core.step(utime, mono, out);
  }
  EXPECT_EQ(core.safety(), Safety::kRunning);
  EXPECT_EQ(out.raw_x[17], 17);
  EXPECT_EQ(out.status[17], 0);
  EXPECT_EQ(core.counters()[Counters::kSamples], 3 * wp::kNumBoards);
  // An FD frame on a classic bus is rejected, not decoded.
  std::array<uint8_t, 32> fd{};
  core.on_frame(wp::sample_id({}, 0), true, fd, mono);
  EXPECT_EQ(core.counters()[Counters::kRejectedWrongFrameType], 1);
}
