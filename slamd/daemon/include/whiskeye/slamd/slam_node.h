// The slamd node: LCM messages in, ViTa-SLAM cycles, LCM messages out. It talks only to Bus
// interfaces, so the same code runs live (LcmBus), on a log (`slamd --replay`) and in unit tests
// (MemoryBus). All of its decisions follow the messages' own sample times, never the wall clock.
//
// In:  WHISK_CYCLE (whisk_cycle_t), CAMERA (image_t), ODOMETRY (odometry_t)
// Out: VITA_POSE   per odometry sample once the first cycle is done (dead-reckoned between cycles)
//      VITA_EVENT, VITA_MATCH  per processed whisk cycle
//      VITA_MAP    when the map changed, at most every map_period_s of data time, and on flush()
//      SLAM_STATUS from publish_status()
// Each channel's name is configurable (NodeChannels: `channel_*` in slam.yaml's `slamd:` section),
// the defaults those of common/channels.h.
#pragma once

#include "whiskeye/slamd/cycle_sync.h"
#include "whiskeye/slamd/node_params.h"

#include "whiskeye/common/bus.h"
#include "whiskeye/common/log_throttle.h"
#include "whiskeye/common/se2.h"
#include "whiskeye/common/sequence_gaps.h"
#include "whiskeye/slam/vita_slam.h"

#include <whiskeye/slam_status_t.hpp>
#include <whiskeye/whisk_cycle_t.hpp>

#include <array>
#include <deque>
#include <functional>
#include <memory>
#include <span>
#include <string>

namespace whiskeye::slamd {

struct NodeCounters {
  int64_t cycles = 0;
  int64_t validation_errors = 0;
  int64_t cycles_without_camera = 0;
  int64_t cycles_without_contact = 0;
  int64_t input_gaps = 0;  // input messages missing by their sequence numbers (all three inputs)
};

class SlamNode {
 public:
  // Called after each processed cycle (e.g. to checkpoint), and for log lines (level, text).
  using CycleHook = std::function<void(const slam::CycleResult&)>;
  using Logger = std::function<void(const std::string& line)>;

  SlamNode(Bus& in, Bus& out, std::unique_ptr<slam::VitaSlam> slam, const NodeParams& params,
           DecodeErrors& decode_errors);

  void set_cycle_hook(CycleHook hook) { cycle_hook_ = std::move(hook); }
  // Log lines, among them each message that does not decode (the node takes DecodeErrors' callback).
  // Repeated warnings are rate-limited (LogThrottle, 10 s per kind, with the count suppressed) on
  // `clock` (default: the monotonic clock).
  void set_logger(Logger logger) { logger_ = std::move(logger); }
  void set_log_clock(std::function<int64_t()> monotonic_us) { log_clock_ = std::move(monotonic_us); }
  // A replay that reads a camera frame's pixels only when a cycle takes it (LogReader::defer):
  // `read_pixels(owner, wanted)` is called with the frame's owner and the part of its pixels the
  // SLAM will read (slam::visual_rows; none in tactile mode) before they are used.
  using PixelReader = std::function<void(const std::shared_ptr<const void>& owner, std::span<const uint8_t> wanted)>;
  void set_pixel_reader(PixelReader read_pixels) { read_pixels_ = std::move(read_pixels); }
  // Wall-clock latency measurement of each cycle (live). Off: latencies stay 0 (deterministic output).
  void set_latency_clock(std::function<int64_t()> monotonic_us) { clock_ = std::move(monotonic_us); }

  // Processes every cycle still pending (end of a log) and publishes the final map.
  void flush();
  // Publishes SLAM_STATUS stamped `utime` (a replay's log time; the 10 s window runs on it too).
  void publish_status(int64_t utime);
  // SLAM_STATUS stamped `utime`: DEGRADED while input was rejected, or (when the mode uses vision)
  // cycles ran without a frame, within the last 10 s of `window_now_us`, OK again after. Live, that
  // is a monotonic clock (a wall-clock step must not end or stretch the window); in a replay, log time.
  slam_status_t status(int64_t utime, int64_t window_now_us);
  slam_status_t status(int64_t utime) { return status(utime, utime); }

  const slam::VitaSlam& slam() const { return *slam_; }
  const NodeCounters& counters() const { return counters_; }

 private:
  void on_camera(std::span<const uint8_t> data, const MessageInfo& info);
  void on_odometry(const odometry_t& msg);
  void on_whisk_cycle(whisk_cycle_t msg);
  void process(std::vector<SyncedCycle> cycles);
  void process_one(const SyncedCycle& cycle);
  void publish_map(int64_t utime);
  // Where a rejection or warning came from: the three inputs, and what the core refused in a cycle.
  enum Input { kCamera, kOdometry, kWhisk, kFrameInCycle, kWhiskInCycle, kInputs };
  // Counts a rejected message (validation_errors) and logs it as log_burst() does.
  void reject(Input input, const std::string& what);
  // The same for a message whose sequence number was read: it arrived, so it is no gap.
  void reject(Input input, int64_t seq, const std::string& what);
  // Logs the first line of a burst on that input (a burst ends at accepted(input)); the rest of the
  // burst goes through the throttle: at most one line per 10 s, saying how many were held back.
  void log_burst(Input input, const std::string& line);
  // A repeated warning of kind `key`, through the throttle.
  void warn(const std::string& key, const std::string& line);
  void accepted(Input input) { rejects_in_burst_[input] = 0; }
  // An accepted message's sequence number (CAMERA.seq, ODOMETRY.seq, WHISK_CYCLE.cycle): messages
  // missing before it were lost on the way (LCM, the network, a recorder), counted and logged.
  void sequence(Input input, int64_t seq);

  Bus& out_;
  std::unique_ptr<slam::VitaSlam> slam_;
  NodeParams params_;
  DecodeErrors& decode_errors_;
  CycleSynchroniser sync_;
  CycleHook cycle_hook_;
  Logger logger_;
  std::function<int64_t()> log_clock_;
  LogThrottle throttle_;
  std::function<int64_t()> clock_;
  PixelReader read_pixels_;
  // Storage kept from cycle to cycle (a cycle is 24 x 500 samples): processed messages to decode the
  // next ones into, and the core's copy of the cycle in hand.
  std::vector<whisk_cycle_t> spare_cycles_;
  slam::WhiskCycleInput whisk_input_;
  NodeCounters counters_;
  SequenceGaps gaps_[kInputs];

  bool have_cycle_ = false;
  Pose2 odom_at_last_cycle_;  // odometry-frame pose at the last processed cycle's end
  int64_t last_map_utime_ = INT64_MIN;
  bool map_dirty_ = false;
  int last_template_id_ = -1;
  bool odometry_overflowing_ = false;  // odometry dropped since the last cycle processed (logged once)
  std::deque<double> latencies_ms_;  // last 1000 cycles
  std::array<int64_t, kInputs> rejects_in_burst_{};
  // A counter's value and the status time it last changed at.
  struct Recent {
    int64_t value = 0;
    int64_t changed_at = INT64_MIN;
    bool changed_within(int64_t now_value, int64_t utime, int64_t window_us);
  };
  Recent recent_errors_, recent_without_camera_;
};

}  // namespace whiskeye::slamd
