// The `based` daemon's wiring, as a class so tests can run it in-process on a MemoryBus:
//   poll thread:    GET /data/odometry at odometry.poll_rate_hz over its own kept-alive connection →
//                   parse → sequence/jump checks → ODOMETRY
//   command thread: BASE_CMD (or the --circle generator) → deadman + limits → POST /data/omnidrive at
//                   command.rate_hz over a second connection (a slow odometry reply must not delay a
//                   command: the base stops itself 200 ms after the last one); zero on exit
//   status thread:  DRIVER_STATUS at 1 Hz, driver "based"
// Faults are counted, logged once per burst to stderr, and never stop the daemon. Each thread beats a
// heartbeat per iteration; check_workers() tells the main loop, which sends the watchdog keep-alive,
// whether all three still run.
#pragma once

#include "whiskeye/based/circle.h"
#include "whiskeye/based/health.h"
#include "whiskeye/based/motion.h"
#include "whiskeye/based/params.h"
#include "whiskeye/based/protocol.h"
#include "whiskeye/based/robotino_client.h"
#include "whiskeye/based/tracker.h"
#include "whiskeye/common/bus.h"
#include "whiskeye/common/channels.h"
#include "whiskeye/common/heartbeats.h"

#include <whiskeye/driver_status_t.hpp>

#include <atomic>
#include <condition_variable>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>

namespace whiskeye::based {

// Channels: ODOMETRY and DRIVER_STATUS out, BASE_CMD in (names from common/channels.h).
class BasedNode {
 public:
  // Throws std::invalid_argument if params.url is not http://host[:port].
  BasedNode(Bus& bus, const BasedParams& params);
  ~BasedNode();
  BasedNode(const BasedNode&) = delete;
  BasedNode& operator=(const BasedNode&) = delete;

  // Drive the circle instead of following BASE_CMD. Call before start(); throws std::invalid_argument.
  void drive_circle(const CircleSpec& spec);

  // Subscribes to BASE_CMD (unless driving a circle) and starts the threads.
  void start();
  // Stops the threads; the command thread sends a zero velocity before it ends. Idempotent.
  void stop();
  // True once a --circle run with laps has completed (and the base has been told to stop).
  bool finished() const { return finished_.load(); }

  // Counter by name (0 if it never counted); names as in DRIVER_STATUS.
  int64_t counter(const std::string& name) const;
  Health::Report health() const;
  // Builds the status message and starts a new statistics interval.
  driver_status_t make_status();

  // Empty while every thread has run within its limit (its longest legitimate block: the retry
  // backoff, the connect and reply timeouts, its period, plus a second); otherwise which thread is
  // silent and for how long. The first call that finds a stall counts `worker_stalls` and logs it.
  // For the loop that sends WATCHDOG=1: withhold it while this is not empty. Call after start().
  std::string check_workers(int64_t now_mono_us);
  // Called at the top of every odometry-thread iteration with a predicate that is true once stop()
  // was called: the seam for the test-only worker stall (based's main passes
  // ServiceNotifier::stall_worker_if_injected). Call before start().
  using PollHook = std::function<void(const std::function<bool()>& stopping)>;
  void set_poll_hook(PollHook hook) { poll_hook_ = std::move(hook); }

 private:
  void poll_loop();
  void command_loop();
  void status_loop();
  void handle_odometry_reply(const Reply& reply);
  void handle_command(const Velocity& v);
  // Counts, logs once per burst and (if `degrades`) shows in the state for degraded_hold_s.
  void count_fault(const std::string& counter, const std::string& detail, bool degrades = true);
  void count(const std::string& name, int64_t n = 1);
  void log_lines();
  bool wait_until(std::chrono::steady_clock::time_point t);  // false when stopping

  Bus& bus_;
  BasedParams params_;
  BaseUrl url_;
  std::optional<CircleTrajectory> circle_;

  mutable std::mutex mutex_;  // everything below that more than one thread touches
  std::map<std::string, int64_t> counters_;
  MotionGate gate_;
  Health health_;
  BurstLog burst_;
  Velocity last_sent_;
  int64_t rtt_sum_us_ = 0;
  int64_t rtt_max_us_ = 0;
  int64_t rtt_count_ = 0;
  int64_t interval_published_ = 0;
  int64_t interval_start_us_ = 0;
  bool stale_ = false;

  std::mutex publish_mutex_;
  DecodeErrors decode_errors_;

  std::mutex wake_mutex_;
  std::condition_variable wake_;
  std::atomic<bool> stopping_{false};
  std::atomic<bool> finished_{false};
  bool started_ = false;
  WorkerHeartbeats beats_;
  int poll_beat_ = -1;
  int command_beat_ = -1;
  int status_beat_ = -1;
  bool stall_reported_ = false;  // check_workers()' caller only
  PollHook poll_hook_;
  std::thread poll_thread_;
  std::thread command_thread_;
  std::thread status_thread_;
};

}  // namespace whiskeye::based
