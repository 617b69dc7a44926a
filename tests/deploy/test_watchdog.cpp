// The daemons under systemd's notify protocol, as real processes: READY=1, then WATCHDOG=1 from the main
// loop at WATCHDOG_USEC/2, none once the loop (or based's odometry thread) is stuck (test-only fault
// injection). camerad runs
// without a camera, based against the fake Robotino server, slamd on an empty bus; whiskerd needs a CAN
// interface and has the same check in the VM (tests/deploy/scenario_whiskerd_watchdog.sh).
// Runs in a private network namespace (LCM udpm:// on loopback).
#include "scratch.h"

#include <gtest/gtest.h>

#include <chrono>
#include <fstream>
#include <thread>

#include "fake_robotino.h"
#include "notify_probe.h"
#include "subprocess.h"

using whiskeye::deploy_testing::check_watchdog;
using whiskeye::deploy_testing::WatchdogCheck;
using whiskeye::deploy_testing::WatchdogReport;

namespace {

void expect_watchdog_contract(const WatchdogReport& r) {
  EXPECT_TRUE(r.ready) << r.summary() << "\n" << r.output;
  EXPECT_TRUE(r.problems.empty()) << r.summary() << "\n" << r.output;
  // The properties themselves, so a failure names the broken one.
  EXPECT_GT(r.pings_in_window, 0) << r.summary();
  EXPECT_TRUE(r.stall_logged) << r.summary();
  EXPECT_EQ(r.pings_after_stall, 0) << r.summary();
  EXPECT_TRUE(r.alive_while_stalled) << r.summary();
}

std::string temp_dir(const std::string& name) { return whiskeye::testing::scratch_dir("deploy_" + name); }

}  // namespace

TEST(Watchdog, CameradWithoutACameraPetsTheWatchdogFromItsLoopAndStopsWhenTheLoopStalls) {
  const WatchdogReport r = check_watchdog({CAMERAD, "--device", "/dev/video-none"}, WatchdogCheck{});
  expect_watchdog_contract(r);
}

TEST(Watchdog, BasedPetsTheWatchdogFromItsLoopAndStopsWhenTheLoopStalls) {
  whiskeye::based::testing::FakeRobotino base;
  const WatchdogReport r = check_watchdog({BASED, "--url", base.url()}, WatchdogCheck{});
  expect_watchdog_contract(r);
  EXPECT_GT(base.odometry_requests(), 0) << "based never talked to the base";
}

TEST(Watchdog, BasedStopsPettingTheWatchdogWhenItsOdometryThreadStalls) {
  // The main loop keeps turning; the keep-alives must stop because a worker does not. Short timeouts
  // make the odometry thread's limit 0.2 + 0.2 + 2 x 0.05 + 0.02 + 1 = 1.52 s.
  whiskeye::based::testing::FakeRobotino base;
  const std::string dir = temp_dir("based_worker");
  const std::string config = dir + "/based.yaml";
  {
    std::ofstream out(config);
    out << "odometry: {connect_timeout_s: 0.2, reply_timeout_s: 0.05}\nconnection: {backoff_max_s: 0.2}\n";
  }
  WatchdogCheck check;
  check.fault = "stall-worker-after";
  check.stall_log = "fault injection: odometry thread stalled";
  check.stall_grace_s = 1.52 + 0.3;
  const WatchdogReport r = check_watchdog({BASED, "--url", base.url(), "--config", config}, check);
  expect_watchdog_contract(r);
  EXPECT_NE(r.output.find("worker_stalls: odometry thread silent for"), std::string::npos) << r.output;
}

TEST(Watchdog, SlamdPetsTheWatchdogFromItsLoopAndStopsWhenTheLoopStalls) {
  const std::string state = temp_dir("slamd_state");
  const WatchdogReport r = check_watchdog({SLAMD, "--state-dir", state}, WatchdogCheck{});
  expect_watchdog_contract(r);
}

TEST(Watchdog, WithoutWatchdogUsecADaemonSendsReadyButNoKeepAlives) {
  whiskeye::deploy_testing::NotifyListener listener;
  whiskeye::testing::Subprocess daemon({CAMERAD, "--device", "/dev/video-none"}, "",
                                       {"NOTIFY_SOCKET=" + listener.path()});
  ASSERT_TRUE(whiskeye::testing::wait_until([&] { return !listener.times_of("READY=1").empty(); }, 10.0))
      << daemon.output();
  std::this_thread::sleep_for(std::chrono::milliseconds(800));
  EXPECT_TRUE(listener.times_of("WATCHDOG=1").empty());
  EXPECT_EQ(daemon.stop(5.0), 0) << daemon.output();
}

TEST(Watchdog, AMalformedFaultInjectionSpecIsRejectedWithTheVariableNamed) {
  whiskeye::testing::Subprocess cam({CAMERAD, "--device", "/dev/video-none"}, "",
                                    {"WHISKEYE_FAULT_INJECT=stall-main-loop-after=soon"});
  EXPECT_NE(cam.wait(10.0), 0);
  EXPECT_NE(cam.output().find("WHISKEYE_FAULT_INJECT"), std::string::npos) << cam.output();
  whiskeye::testing::Subprocess slam({SLAMD, "--state-dir", temp_dir("bad_spec")}, "",
                                     {"WHISKEYE_FAULT_INJECT=crash"});
  EXPECT_NE(slam.wait(10.0), 0);
  EXPECT_NE(slam.output().find("WHISKEYE_FAULT_INJECT"), std::string::npos) << slam.output();
}
