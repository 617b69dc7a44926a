// Integration tests of the based daemon logic, in-process on a MemoryBus, against a Robotino REST
// server on 127.0.0.1 (fake_robotino.h) with scripted faults.
#include "fake_robotino.h"

#include "whiskeye/based/node.h"
#include "whiskeye/common/clock.h"
#include "whiskeye/common/se2.h"
#include "whiskeye/common/service.h"

#include <whiskeye/base_cmd_t.hpp>
#include <whiskeye/odometry_t.hpp>

#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <functional>
#include <limits>
#include <memory>
#include <mutex>
#include <thread>

namespace whiskeye::based {
namespace {

using testing::FakeRobotino;
using testing::Fault;

// Fast rates and short timeouts so each test takes a fraction of a second to a few seconds.
BasedParams test_params(const std::string& url) {
  BasedParams p;
  p.url = url;
  p.odometry.poll_rate_hz = 100.0;
  p.odometry.reply_timeout_s = 0.05;
  p.odometry.connect_timeout_s = 0.05;
  p.command.rate_hz = 50.0;
  p.command.reply_timeout_s = 0.05;
  p.command.deadman_s = 0.2;
  p.command.max_linear_speed = 0.5;
  p.command.max_angular_speed = 1.5;
  p.command.max_linear_accel = 2.0;
  p.command.max_angular_accel = 4.0;
  p.connection.backoff_initial_s = 0.02;
  p.connection.backoff_max_s = 0.1;
  p.connection.fault_after_s = 0.3;
  p.connection.degraded_hold_s = 0.3;
  return p;
}

bool wait_for(const std::function<bool()>& done, double timeout_s = 3.0) {
  const auto end = std::chrono::steady_clock::now() + std::chrono::duration<double>(timeout_s);
  while (std::chrono::steady_clock::now() < end) {
    if (done()) return true;
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  return done();
}

// Collects what the node publishes (from its threads).
struct Collector {
  explicit Collector(MemoryBus& bus) {
    subscribe<odometry_t>(bus, channels::kOdometry, [this](const odometry_t& m) {
      std::lock_guard<std::mutex> lock(mutex);
      odometry.push_back(m);
    }, errors);
    subscribe<driver_status_t>(bus, channels::kDriverStatus, [this](const driver_status_t& m) {
      std::lock_guard<std::mutex> lock(mutex);
      status.push_back(m);
    }, errors);
  }
  std::vector<odometry_t> odom() {
    std::lock_guard<std::mutex> lock(mutex);
    return odometry;
  }
  std::size_t odom_count() { return odom().size(); }
  std::vector<driver_status_t> statuses() {
    std::lock_guard<std::mutex> lock(mutex);
    return status;
  }
  std::mutex mutex;
  std::vector<odometry_t> odometry;
  std::vector<driver_status_t> status;
  DecodeErrors errors;
};

int64_t status_counter(const driver_status_t& s, const std::string& name) {
  for (int i = 0; i < s.num_counters; ++i) {
    if (s.counter_names[i] == name) return s.counter_values[i];
  }
  ADD_FAILURE() << "no counter " << name << " in DRIVER_STATUS";
  return -1;
}

void send_cmd(MemoryBus& bus, double vx, double vy, double omega) {
  base_cmd_t c{};
  c.utime = now_utime();
  c.vx = vx;
  c.vy = vy;
  c.omega = omega;
  publish(bus, channels::kBaseCmd, c);
}

// Every published sample equals what the base reported for its seq (identity offset, wrapped theta).
void expect_matches_base(const odometry_t& m) {
  const testing::FakePose p = FakeRobotino::expected_pose(m.seq);
  EXPECT_NEAR(m.x, p.x, 1e-12) << "seq " << m.seq;
  EXPECT_NEAR(m.y, p.y, 1e-12) << "seq " << m.seq;
  EXPECT_NEAR(m.theta, wrap_angle(p.theta), 1e-12) << "seq " << m.seq;
  EXPECT_GT(m.theta, -kPi);
  EXPECT_LE(m.theta, kPi);
  EXPECT_EQ(m.vx, p.vx);
  EXPECT_EQ(m.vy, p.vy);
  EXPECT_EQ(m.omega, p.omega);
}

// A fake base, a bus and what the node publishes; the node is destroyed first (members in reverse).
struct BasedNodeTest : public ::testing::Test {
  BasedNode& make(const BasedParams& p) {
    node = std::make_unique<BasedNode>(bus, p);
    return *node;
  }
  BasedNode& start(const BasedParams& p) {
    make(p).start();
    return *node;
  }
  BasedNode& start() { return start(test_params(base.url())); }
  // A reset must be counted once and ODOMETRY must not jump with the base's origin.
  void expect_reset_handled(Fault fault, const char* counter);
  bool samples(std::size_t n) {
    return wait_for([&] { return got.odom_count() >= n; });
  }

  FakeRobotino base;
  MemoryBus bus;
  Collector got{bus};
  std::unique_ptr<BasedNode> node;
};

TEST_F(BasedNodeTest, PublishesOdometryOverOneKeptAliveConnection) {
  BasedNode& node = start();
  // 0.01 s per seq at omega 0.5 from theta 3.0: theta passes pi after ~28 samples.
  ASSERT_TRUE(samples(40));
  node.stop();
  const std::vector<odometry_t> odom = got.odom();
  int64_t prev_seq = -1;
  bool crossed_pi = false;
  for (const odometry_t& m : odom) {
    expect_matches_base(m);
    EXPECT_GT(m.seq, prev_seq);
    prev_seq = m.seq;
    crossed_pi = crossed_pi || m.theta < 0.0;
  }
  EXPECT_TRUE(crossed_pi);
  EXPECT_EQ(odom.front().seq, FakeRobotino::kFirstSeq);
  EXPECT_EQ(node.counter("connections_opened"), 1);
  EXPECT_EQ(node.counter("odometry_published"), static_cast<int64_t>(odom.size()));
  for (const char* c : {"reply_timeouts", "replies_dropped", "replies_malformed", "repeated_seq",
                        "odometry_resets", "connect_failures"}) {
    EXPECT_EQ(node.counter(c), 0) << c;
  }
}

TEST_F(BasedNodeTest, ServerClosingTheKeptAliveConnectionIsNotAFault) {
  FakeRobotino closing(0, 5);  // cpp-httplib's default: 5 requests per connection
  BasedNode& node = start(test_params(closing.url()));
  ASSERT_TRUE(samples(30));
  node.stop();
  EXPECT_GE(node.counter("connections_opened"), 5);
  EXPECT_EQ(node.counter("replies_dropped"), 0);
  EXPECT_EQ(node.counter("reply_timeouts"), 0);
  EXPECT_EQ(node.counter("command_failures"), 0);
  for (const odometry_t& m : got.odom()) expect_matches_base(m);
}

TEST_F(BasedNodeTest, StampsOdometryAtTheMiddleOfTheRoundTrip) {
  base.set_reply_delay_ms(15);  // the base samples 15 ms after the request and replies 15 ms later
  BasedNode& node = start();
  ASSERT_TRUE(samples(10));
  node.stop();
  std::vector<double> errors_us;
  for (const odometry_t& m : got.odom()) {
    const int64_t truth = base.sample_utime(m.seq);
    ASSERT_NE(truth, 0);
    errors_us.push_back(static_cast<double>(m.utime - truth));
  }
  // Stamping at reception would be ~15 ms late; the mid-round-trip stamp is right up to scheduling
  // noise (the median, so a loaded machine's odd late wake-up does not decide the test).
  std::sort(errors_us.begin(), errors_us.end());
  EXPECT_NEAR(errors_us[errors_us.size() / 2], 0.0, 5000.0);
}

TEST_F(BasedNodeTest, CountsMalformedRepliesAndCarriesOn) {
  base.script({Fault::kMalformed, Fault::kWrongLength, Fault::kNaN, Fault::kNull, Fault::kHttp500});
  BasedNode& node = start();
  ASSERT_TRUE(samples(10));
  node.stop();
  EXPECT_EQ(node.counter("replies_malformed"), 4);
  EXPECT_EQ(node.counter("http_errors"), 1);
  for (const odometry_t& m : got.odom()) expect_matches_base(m);
  EXPECT_EQ(node.counter("connections_opened"), 1);
}

TEST_F(BasedNodeTest, SlowReplyIsATimeoutAndThePollerCarriesOn) {
  base.set_slow_reply_ms(120);  // > reply_timeout_s 0.05
  base.script({Fault::kSlow});
  BasedNode& node = start();
  ASSERT_TRUE(samples(10));
  node.stop();
  EXPECT_EQ(node.counter("reply_timeouts"), 1);
  EXPECT_EQ(node.counter("replies_dropped"), 0);
  EXPECT_EQ(node.counter("connections_opened"), 2) << "a timed-out connection is replaced";
  for (const odometry_t& m : got.odom()) expect_matches_base(m);
}

TEST_F(BasedNodeTest, DroppedConnectionIsCountedAndReconnected) {
  base.script({Fault::kDrop, Fault::kDrop});
  BasedNode& node = start();
  ASSERT_TRUE(samples(10));
  node.stop();
  EXPECT_EQ(node.counter("replies_dropped"), 2);
  EXPECT_EQ(node.counter("reply_timeouts"), 0);
  EXPECT_EQ(node.counter("connections_opened"), 3);
  for (const odometry_t& m : got.odom()) expect_matches_base(m);
}

TEST_F(BasedNodeTest, RepeatedSeqIsCountedAndNotPublished) {
  BasedNode& node = start();
  ASSERT_TRUE(samples(3));
  base.script({Fault::kRepeatSeq, Fault::kRepeatSeq, Fault::kRepeatSeq});
  ASSERT_TRUE(samples(10));
  node.stop();
  EXPECT_EQ(node.counter("repeated_seq"), 3);
  EXPECT_EQ(node.health().state, HealthState::kOk) << "a few repeats are routine, not a fault";
  int64_t prev = -1;
  for (const odometry_t& m : got.odom()) {
    EXPECT_GT(m.seq, prev);
    prev = m.seq;
  }
}

TEST_F(BasedNodeTest, FrozenOdometryIsStaleOnceAndDegraded) {
  BasedParams p = test_params(base.url());
  p.odometry.stale_after_s = 0.1;
  BasedNode& node = start(p);
  ASSERT_TRUE(samples(3));
  base.script(std::vector<Fault>(40, Fault::kRepeatSeq));  // 0.4 s of the same seq at 100 Hz
  ASSERT_TRUE(wait_for([&] { return node.health().state == HealthState::kDegraded; }));
  EXPECT_NE(node.health().message.find("stale"), std::string::npos) << node.health().message;
  ASSERT_TRUE(wait_for([&] { return node.counter("repeated_seq") == 40; }));
  ASSERT_TRUE(samples(got.odom_count() + 3));
  node.stop();
  EXPECT_EQ(node.counter("stale_events"), 1);
}

void BasedNodeTest::expect_reset_handled(Fault fault, const char* counter) {
  BasedNode& node = start();
  ASSERT_TRUE(samples(5));
  base.script({fault});
  const std::size_t before = got.odom_count();
  ASSERT_TRUE(samples(before + 10));
  node.stop();
  EXPECT_EQ(node.counter(counter), 1);
  EXPECT_EQ(node.counter("odometry_resets"), 1);
  const std::vector<odometry_t> odom = got.odom();
  for (std::size_t i = 1; i < odom.size(); ++i) {
    // The base moves 2.2 mm per sample; a missed poll at most doubles that. 5 m must not show.
    EXPECT_LT(std::hypot(odom[i].x - odom[i - 1].x, odom[i].y - odom[i - 1].y), 0.05) << "at " << i;
  }
}

TEST_F(BasedNodeTest, OdometryJumpIsAResetAndOdometryStaysContinuous) {
  expect_reset_handled(Fault::kJump, "odometry_jumps");
}

TEST_F(BasedNodeTest, SeqGoingBackwardsIsAReset) { expect_reset_handled(Fault::kSeqRestart, "seq_backwards"); }

TEST_F(BasedNodeTest, UnreachableBaseIsAFaultWithAMessageAndRecovers) {
  int port = 0;
  {
    FakeRobotino probe;  // find a free port, then close it
    port = probe.port();
  }
  BasedNode& node = start(test_params("http://127.0.0.1:" + std::to_string(port)));
  ASSERT_TRUE(wait_for([&] { return node.health().state == HealthState::kFault; }));
  const Health::Report down = node.health();
  EXPECT_NE(down.message.find("cannot connect"), std::string::npos) << down.message;
  const driver_status_t status = node.make_status();
  EXPECT_EQ(status.driver, "based");
  EXPECT_EQ(int{status.state}, int{driver_status_t::STATE_FAULT});
  EXPECT_NE(status.message.find("127.0.0.1:" + std::to_string(port)), std::string::npos) << status.message;
  const int64_t failures = node.counter("connect_failures");
  EXPECT_GE(failures, 2);
  // Backoff: 0.3+ s at 100 Hz would be 30 attempts without it.
  EXPECT_LE(failures, 12);
  EXPECT_EQ(got.odom_count(), 0u);

  FakeRobotino revived(port);
  ASSERT_TRUE(samples(5));
  ASSERT_TRUE(wait_for([&] { return node.health().state == HealthState::kOk; }, 2.0)) << node.health().message;
  node.stop();
}

TEST_F(BasedNodeTest, ABaseReachedAfterAnOutageIsRampedUpFromRestNotSentTheGatesSpeed) {
  int port = 0;
  {
    FakeRobotino probe;  // a free port, closed: the base is unreachable while BASE_CMD streams
    port = probe.port();
  }
  BasedParams p = test_params("http://127.0.0.1:" + std::to_string(port));
  p.command.max_linear_accel = 1.0;
  BasedNode& node = start(p);
  auto stream_for = [&](std::chrono::milliseconds how_long, const std::function<bool()>& until) {
    const auto end = std::chrono::steady_clock::now() + how_long;
    while (std::chrono::steady_clock::now() < end && !until()) {
      send_cmd(bus, 3.0, 4.0, 0.0);  // 0.5 m/s after clamping: 0.5 s of ramp at 1 m/s²
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
  };
  stream_for(std::chrono::milliseconds(800), [] { return false; });
  FakeRobotino revived(port);
  stream_for(std::chrono::milliseconds(5000), [&] { return revived.commands().size() >= 5; });
  node.stop();
  const std::vector<testing::ReceivedCommand> cmds = revived.commands();
  ASSERT_GE(cmds.size(), 5u);
  // The gate bounds its own dt by two periods: the first command the base gets is one such step.
  EXPECT_LE(std::hypot(cmds[0].vx, cmds[0].vy), 1.0 * 2.0 / 50.0 + 1e-9);
  EXPECT_GT(std::hypot(cmds[3].vx, cmds[3].vy), 0.0);
}

TEST_F(BasedNodeTest, AnUnreachableBaseIsNotAStalledThread) {
  // Connect failures and the retry backoff are a thread doing its job: the watchdog must not fire.
  int port = 0;
  {
    FakeRobotino probe;
    port = probe.port();
  }
  BasedNode& node = start(test_params("http://127.0.0.1:" + std::to_string(port)));
  const auto end = std::chrono::steady_clock::now() + std::chrono::milliseconds(2500);
  while (std::chrono::steady_clock::now() < end) {
    ASSERT_EQ(node.check_workers(monotonic_us()), "");
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  EXPECT_GE(node.counter("connect_failures"), 5);
  EXPECT_EQ(node.counter("worker_stalls"), 0);
  node.stop();
}

TEST_F(BasedNodeTest, AStalledOdometryThreadIsReportedOnceWhileTheOthersRun) {
  // The daemon's own wiring: the service's test-only worker stall, due 300 ms after start.
  ::setenv(kFaultInjectEnv, "stall-worker-after=300ms", 1);
  ServiceNotifier service("based-test", monotonic_us());
  ::unsetenv(kFaultInjectEnv);
  BasedNode& node = make(test_params(base.url()));
  node.set_poll_hook([&service](const std::function<bool()>& stopping) {
    service.stall_worker_if_injected(monotonic_us(), "odometry thread", stopping);
  });
  node.start();
  ASSERT_TRUE(samples(5));
  EXPECT_EQ(node.check_workers(monotonic_us()), "");
  // Limit with test_params: backoff 0.1 + connect 0.05 + 2 x reply 0.05 + period 0.01 + 1 s slack.
  std::string stalled;
  ASSERT_TRUE(wait_for([&] { return !(stalled = node.check_workers(monotonic_us())).empty(); }, 4.0));
  EXPECT_NE(stalled.find("odometry thread silent for"), std::string::npos) << stalled;
  EXPECT_NE(stalled.find("limit 1.26 s"), std::string::npos) << stalled;
  const int64_t requests = base.odometry_requests();
  const int64_t sent = node.counter("commands_sent");
  std::this_thread::sleep_for(std::chrono::milliseconds(300));
  EXPECT_NE(node.check_workers(monotonic_us()), "");
  EXPECT_EQ(node.counter("worker_stalls"), 1) << "counted once per stall, not per check";
  EXPECT_EQ(base.odometry_requests(), requests) << "the stalled thread still polls";
  EXPECT_GT(node.counter("commands_sent"), sent) << "the command thread stopped too";
  EXPECT_EQ(status_counter(node.make_status(), "worker_stalls"), 1);
  node.stop();  // ends the stall
}

TEST_F(BasedNodeTest, PublishesDriverStatusOncePerSecond) {
  BasedParams p = test_params(base.url());
  p.connection.degraded_hold_s = 1.5;  // longer than the status period: every fault shows in one status
  BasedNode& node = start(p);
  ASSERT_TRUE(wait_for([&] { return got.statuses().size() >= 1; }, 1.5));
  base.script({Fault::kMalformed});
  ASSERT_TRUE(wait_for([&] { return got.statuses().size() >= 2; }, 1.5));
  node.stop();
  const std::vector<driver_status_t> s = got.statuses();
  EXPECT_EQ(s[0].driver, "based");
  EXPECT_EQ(int{s[0].state}, int{driver_status_t::STATE_OK}) << s[0].message;
  EXPECT_GT(status_counter(s[0], "odometry_published"), 20);
  EXPECT_EQ(status_counter(s[1], "replies_malformed"), 1);
  EXPECT_EQ(int{s[1].state}, int{driver_status_t::STATE_DEGRADED});
  EXPECT_NE(s[1].message.find("not JSON"), std::string::npos) << s[1].message;
  EXPECT_NEAR(static_cast<double>(s[1].utime - s[0].utime), 1e6, 0.3e6) << "1 Hz (a loaded runner delays a wake-up)";
  ASSERT_EQ(s[0].num_stats, static_cast<int32_t>(s[0].stat_names.size()));
  EXPECT_EQ(s[0].stat_names[0], "odometry_rate_hz");
  EXPECT_GT(s[0].stat_values[0], 20.0);
}

// ---- commands ----

TEST_F(BasedNodeTest, DeadmanStopsTheBaseWhenCommandsStop) {
  const BasedParams p = test_params(base.url());
  BasedNode& node = start(p);
  for (int i = 0; i < 15; ++i) {  // 0.3 s of commands at 50 Hz
    send_cmd(bus, 0.3, 0.0, 0.0);
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  const int64_t last_cmd = monotonic_us();
  ASSERT_TRUE(wait_for([&] {
    const auto c = base.commands();
    return !c.empty() && c.back().mono_us > last_cmd + 300'000;
  }));
  node.stop();
  const std::vector<testing::ReceivedCommand> cmds = base.commands();
  bool moved = false;
  for (const auto& c : cmds) {
    moved = moved || c.vx > 0.25;
    if (c.mono_us > last_cmd + static_cast<int64_t>(p.command.deadman_s * 1e6) + 3 * 20'000) {
      EXPECT_EQ(c.vx, 0.0) << "still moving " << (c.mono_us - last_cmd) / 1000 << " ms after the last BASE_CMD";
    }
  }
  EXPECT_TRUE(moved);
  EXPECT_EQ(node.counter("deadman_stops"), 1);
}

TEST_F(BasedNodeTest, LimitsSpeedAndAcceleration) {
  BasedParams p = test_params(base.url());
  p.command.max_linear_accel = 1.0;
  BasedNode& node = start(p);
  const auto end = std::chrono::steady_clock::now() + std::chrono::milliseconds(800);
  while (std::chrono::steady_clock::now() < end) {
    send_cmd(bus, 3.0, 4.0, -9.0);  // 5 m/s and 9 rad/s asked, limits are 0.5 and 1.5
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  node.stop();
  const std::vector<testing::ReceivedCommand> cmds = base.commands();
  ASSERT_GT(cmds.size(), 20u);
  double prev_speed = 0.0;
  double prev_omega = 0.0;
  double top = 0.0;
  for (std::size_t i = 0; i + 1 < cmds.size(); ++i) {  // the last is the zero at stop
    const auto& c = cmds[i];
    const double speed = std::hypot(c.vx, c.vy);
    EXPECT_LE(speed, 0.5 + 1e-9);
    EXPECT_LE(std::abs(c.omega), 1.5 + 1e-9);
    // The gate bounds its own dt by two periods, so one step changes by at most accel · 2 / rate.
    EXPECT_LE(speed - prev_speed, 1.0 * 2.0 / 50.0 + 1e-9) << "at " << i;
    EXPECT_LE(std::abs(c.omega - prev_omega), 4.0 * 2.0 / 50.0 + 1e-9) << "at " << i;
    if (speed > 0.0) {
      EXPECT_NEAR(c.vy / c.vx, 4.0 / 3.0, 1e-9);
    }
    prev_speed = speed;
    prev_omega = c.omega;
    top = std::max(top, speed);
  }
  EXPECT_NEAR(top, 0.5, 1e-9);
  EXPECT_EQ(cmds.back().vx, 0.0);
  EXPECT_EQ(cmds.back().omega, 0.0);
}

TEST_F(BasedNodeTest, NonFiniteCommandIsRejectedAndNeverSent) {
  BasedNode& node = start();
  ASSERT_TRUE(samples(1));  // past STARTING
  send_cmd(bus, 0.1, 0.0, 0.0);
  send_cmd(bus, std::numeric_limits<double>::quiet_NaN(), 0.0, 0.0);
  const Health::Report report = node.health();  // the bus hands BASE_CMD over synchronously
  EXPECT_EQ(report.state, HealthState::kDegraded) << "bad input is worth a look";
  EXPECT_NE(report.message.find("commands_rejected"), std::string::npos) << report.message;
  ASSERT_TRUE(wait_for([&] { return base.commands().size() >= 5; }));
  node.stop();
  EXPECT_EQ(node.counter("commands_received"), 2);
  EXPECT_EQ(node.counter("commands_rejected"), 1);
  EXPECT_EQ(node.counter("command_failures"), 0) << "the base got a body it could not parse";
}

TEST_F(BasedNodeTest, StopSendsAZeroVelocity) {
  BasedNode& node = start();
  for (int i = 0; i < 10; ++i) {
    send_cmd(bus, 0.0, 0.2, 0.3);
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  ASSERT_GT(base.commands().back().vy, 0.0);
  node.stop();
  const auto c = base.commands().back();
  EXPECT_EQ(c.vx, 0.0);
  EXPECT_EQ(c.vy, 0.0);
  EXPECT_EQ(c.omega, 0.0);
}

TEST_F(BasedNodeTest, CircleCommandsSidewaysMotionAndStopsAfterTheLaps) {
  const BasedParams p = test_params(base.url());
  BasedNode& node = make(p);
  const double radius = 0.4, speed = -0.5;  // clockwise; 1.25 rad/s
  node.drive_circle(CircleSpec{radius, speed, 1});
  send_cmd(bus, 0.3, 0.0, 0.0);  // ignored while driving the circle
  node.start();
  send_cmd(bus, 0.3, 0.0, 0.0);
  // 2.51 m at 0.5 m/s with 0.25 s ramps: ~5.3 s. Too long for this suite: watch the first 1.5 s.
  ASSERT_TRUE(wait_for([&] { return base.commands().size() >= 60; }));
  EXPECT_FALSE(node.finished());
  node.stop();
  const auto cmds = base.commands();
  double prev = 0.0;
  bool cruised = false;
  for (std::size_t i = 0; i + 1 < cmds.size(); ++i) {
    const auto& c = cmds[i];
    EXPECT_EQ(c.vx, 0.0);
    EXPECT_LE(c.vy, 0.0);
    if (c.vy != 0.0) {
      EXPECT_NEAR(c.vy / c.omega, radius, 1e-9) << "off the circle at " << i;
    }
    EXPECT_LE(std::abs(c.vy - prev), p.command.max_linear_accel * 2.0 / p.command.rate_hz + 1e-9);
    prev = c.vy;
    cruised = cruised || std::abs(c.vy - speed) < 1e-12;
  }
  EXPECT_TRUE(cruised);
  EXPECT_EQ(node.counter("commands_received"), 0);
}

TEST_F(BasedNodeTest, CircleWithLapsFinishesAndLeavesTheBaseStopped) {
  BasedParams p = test_params(base.url());
  p.command.max_angular_speed = 6.0;
  p.command.max_angular_accel = 20.0;
  BasedNode& node = make(p);
  const double radius = 0.1, speed = 0.5;  // 0.63 m: 0.25 s ramps and 1 s of cruise
  node.drive_circle(CircleSpec{radius, speed, 1});
  node.start();
  ASSERT_TRUE(wait_for([&] { return node.finished(); }, 4.0));
  const auto cmds = base.commands();
  node.stop();
  ASSERT_GT(cmds.size(), 30u);
  // What the base was told adds up to one lap: arc length and heading change.
  double arc = 0.0;
  double turned = 0.0;
  for (std::size_t i = 0; i + 1 < cmds.size(); ++i) {
    const double dt = static_cast<double>(cmds[i + 1].mono_us - cmds[i].mono_us) * 1e-6;
    arc += cmds[i].vy * dt;
    turned += cmds[i].omega * dt;
    EXPECT_EQ(cmds[i].vx, 0.0);
    EXPECT_GE(cmds[i].vy, 0.0);
  }
  EXPECT_NEAR(arc, kTwoPi * radius, 0.1 * kTwoPi * radius);
  EXPECT_NEAR(turned, kTwoPi, 0.1 * kTwoPi);
  EXPECT_EQ(cmds.back().vy, 0.0);
  EXPECT_EQ(cmds.back().omega, 0.0);
}

}  // namespace
}  // namespace whiskeye::based
