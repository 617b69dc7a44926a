// ServiceNotifier in-process: the fault-injection spec parser, and the keep-alive rate against a
// notify socket owned by the test (sd_notify reads NOTIFY_SOCKET and WATCHDOG_USEC at each call).
#include <gtest/gtest.h>

#include <cstdlib>
#include <functional>
#include <stdexcept>
#include <thread>

#include <whiskeye/common/heartbeats.h>
#include <whiskeye/common/service.h>

#include "notify_probe.h"
#include "subprocess.h"

using whiskeye::FaultInjection;
using whiskeye::parse_fault_injection;
using whiskeye::ServiceNotifier;

TEST(FaultInjection, EmptySpecIsOff) { EXPECT_FALSE(parse_fault_injection("").any()); }

TEST(FaultInjection, StallAfterSecondsOrMilliseconds) {
  EXPECT_EQ(parse_fault_injection("stall-main-loop-after=2s").stall_main_loop_after_us, 2000000);
  EXPECT_EQ(parse_fault_injection("stall-main-loop-after=1.5s").stall_main_loop_after_us, 1500000);
  EXPECT_EQ(parse_fault_injection("stall-main-loop-after=250ms").stall_main_loop_after_us, 250000);
  EXPECT_EQ(parse_fault_injection("stall-main-loop-after=0s").stall_main_loop_after_us, 0);
}

TEST(FaultInjection, MalformedSpecsThrowNamingTheVariable) {
  for (const char* bad : {"stall", "stall-main-loop-after=", "stall-main-loop-after=2", "stall-main-loop-after=2h",
                          "stall-main-loop-after=-1s", "stall-main-loop-after=nans", "crash-after=1s"}) {
    try {
      parse_fault_injection(bad);
      ADD_FAILURE() << bad << " accepted";
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find("WHISKEYE_FAULT_INJECT"), std::string::npos) << e.what();
    }
  }
}

namespace {
// Sets the variables for this process and restores them, so tests stay independent.
class ScopedEnv {
 public:
  ScopedEnv(const char* name, const std::string& value) : name_(name) { ::setenv(name, value.c_str(), 1); }
  ~ScopedEnv() { ::unsetenv(name_); }

 private:
  const char* name_;
};
}  // namespace

TEST(ServiceNotifier, KeepAlivesAreSentAtHalfTheWatchdogIntervalAndNoFaster) {
  whiskeye::deploy_testing::NotifyListener listener;
  ScopedEnv socket("NOTIFY_SOCKET", listener.path());
  ScopedEnv usec("WATCHDOG_USEC", "1000000");
  ServiceNotifier service("test", 0);
  ASSERT_TRUE(service.watchdog_enabled());
  EXPECT_EQ(service.keep_alive_interval_us(), 500000);
  service.ready("testing");
  int sent = 0;
  // A loop turning every 100 ms for 3 s (synthetic time): one keep-alive per 500 ms.
  for (int64_t t = 0; t <= 3000000; t += 100000) sent += service.keep_alive(t) ? 1 : 0;
  EXPECT_EQ(sent, 7);  // t = 0, 0.5, ..., 3.0 s
  EXPECT_TRUE(whiskeye::testing::wait_until([&] { return listener.times_of("WATCHDOG=1").size() == 7; }, 2.0));
  EXPECT_EQ(listener.times_of("READY=1").size(), 1u);
  bool status = false;
  for (const auto& m : listener.messages()) status = status || m.text == "STATUS=testing";
  EXPECT_TRUE(status);
}

TEST(ServiceNotifier, WithoutWatchdogUsecNothingIsSentByKeepAlive) {
  whiskeye::deploy_testing::NotifyListener listener;
  ScopedEnv socket("NOTIFY_SOCKET", listener.path());
  ::unsetenv("WATCHDOG_USEC");
  ServiceNotifier service("test", 0);
  EXPECT_FALSE(service.watchdog_enabled());
  for (int64_t t = 0; t <= 2000000; t += 100000) EXPECT_FALSE(service.keep_alive(t));
  std::this_thread::sleep_for(std::chrono::milliseconds(100));
  EXPECT_TRUE(listener.times_of("WATCHDOG=1").empty());
}

TEST(ServiceNotifier, WithoutInjectionTheStallNeverBlocks) {
  ::unsetenv("WHISKEYE_FAULT_INJECT");
  ServiceNotifier service("test", 0);
  int polls = 0;
  service.stall_if_injected(1'000'000'000, [&] { return ++polls > 0; });
  EXPECT_EQ(polls, 0);
}

namespace {

// The contract of either injected stall, due 1 s after a start at 5 s: it does not block before it is
// due; once due it blocks until the stop predicate is true (polled); released, it never blocks again,
// so the daemon can shut down. `stall` is the stall under test, called as the daemon's loop would.
using Stall = std::function<void(int64_t now_us, const std::function<bool()>& stop)>;
void expect_blocks_once_when_due(const Stall& stall) {
  int polls = 0;
  stall(5'900'000, [&] { return ++polls > 0; });
  EXPECT_EQ(polls, 0) << "stalled before it was due";
  stall(6'000'000, [&] { return ++polls >= 3; });
  EXPECT_EQ(polls, 3);
  stall(7'000'000, [&] { return ++polls > 100; });
  EXPECT_EQ(polls, 3) << "stalled twice";
}

}  // namespace

TEST(ServiceNotifier, InjectedStallBlocksOnceDueUntilStopIsRequested) {
  ScopedEnv spec("WHISKEYE_FAULT_INJECT", "stall-main-loop-after=1s");
  ServiceNotifier service("test", 5'000'000);
  expect_blocks_once_when_due(
      [&](int64_t now, const std::function<bool()>& stop) { service.stall_if_injected(now, stop); });
}

TEST(ServiceNotifier, InjectedWorkerStallBlocksThatWorkerOnceAndLeavesTheMainLoopAlone) {
  ScopedEnv spec("WHISKEYE_FAULT_INJECT", "stall-worker-after=1s");
  ServiceNotifier service("test", 5'000'000);
  int polls = 0;
  service.stall_if_injected(9'000'000, [&] { return ++polls > 0; });
  EXPECT_EQ(polls, 0) << "the main loop stalled on a worker's fault";
  expect_blocks_once_when_due([&](int64_t now, const std::function<bool()>& stop) {
    service.stall_worker_if_injected(now, "odometry thread", stop);
  });
}

TEST(FaultInjection, ParsesBothStallsAndRejectsAnUnknownFaultNamingTheKnownOnes) {
  const FaultInjection main_loop = parse_fault_injection("stall-main-loop-after=2s");
  EXPECT_EQ(main_loop.stall_main_loop_after_us, 2'000'000);
  EXPECT_EQ(main_loop.stall_worker_after_us, -1);
  const FaultInjection worker = parse_fault_injection("stall-worker-after=250ms");
  EXPECT_EQ(worker.stall_worker_after_us, 250'000);
  EXPECT_EQ(worker.stall_main_loop_after_us, -1);
  EXPECT_TRUE(worker.any());
  EXPECT_FALSE(parse_fault_injection("").any());
  try {
    parse_fault_injection("stall-everything-after=1s");
    FAIL() << "accepted an unknown fault";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("stall-worker-after="), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("stall-main-loop-after="), std::string::npos) << e.what();
  }
  EXPECT_THROW(parse_fault_injection("stall-worker-after=soon"), std::invalid_argument);
}

TEST(WorkerHeartbeats, AWorkerIsStalledOnlyAfterItsOwnLimitAndAliveAgainOnceItBeats) {
  whiskeye::WorkerHeartbeats beats;
  const int fast = beats.add("poll", 1'000'000, 0);
  const int slow = beats.add("status", 3'000'000, 0);
  EXPECT_EQ(beats.stalled(1'000'000), "") << "exactly at the limit is still alive";
  EXPECT_EQ(beats.stalled(1'500'000), "poll thread silent for 1.50 s (limit 1.00 s)");
  beats.beat(fast, 1'400'000);
  EXPECT_EQ(beats.stalled(1'500'000), "");
  beats.beat(fast, 3'200'000);
  EXPECT_EQ(beats.stalled(3'200'001), "status thread silent for 3.20 s (limit 3.00 s)");
  beats.beat(slow, 3'300'000);
  EXPECT_EQ(beats.stalled(3'300'000), "");
  EXPECT_THROW(beats.add("bad", 0, 0), std::invalid_argument);
}
