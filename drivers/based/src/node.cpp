// The `based` daemon's threads: odometry poller, command sender, status publisher.
#include "whiskeye/based/node.h"

#include "whiskeye/common/clock.h"
#include "whiskeye/common/log.h"
#include "whiskeye/common/utime.h"

#include <whiskeye/base_cmd_t.hpp>
#include <whiskeye/odometry_t.hpp>

#include <algorithm>
#include <cstdio>
#include <stdexcept>

namespace whiskeye::based {

namespace {

// Counter names in the order DRIVER_STATUS lists them.
const char* const kCounterNames[] = {
    "odometry_published", "replies_ok",        "reply_timeouts",  "replies_dropped",
    "connect_failures",   "http_errors",       "replies_malformed", "repeated_seq",
    "seq_backwards",      "odometry_jumps",    "odometry_resets", "stale_events",
    "connections_opened", "commands_received", "commands_rejected", "commands_sent",
    "command_failures",   "deadman_stops",     "decode_errors",     "worker_stalls",
};

// Added to each thread's longest legitimate block before it counts as stalled.
constexpr double kWorkerSlackS = 1.0;

// Each line with its journal priority (common/log.h): faults are warnings, recoveries and states notices.
void based_log(LogLevel level, const std::string& line) { log_line(level, "based: " + line); }

std::chrono::steady_clock::duration seconds(double s) {
  return std::chrono::duration_cast<std::chrono::steady_clock::duration>(std::chrono::duration<double>(s));
}

BaseUrl parse_url_or_throw(const std::string& url) {
  BaseUrl out;
  std::string error;
  if (!parse_base_url(url, out, error)) throw std::invalid_argument(error);
  return out;
}

}  // namespace

BasedNode::BasedNode(Bus& bus, const BasedParams& params)
    : bus_(bus),
      params_(params),
      url_(parse_url_or_throw(params.url)),
      gate_(params.command),
      health_(params.connection, params.odometry, monotonic_us()),
      burst_(params.connection.log_quiet_s) {
  interval_start_us_ = monotonic_us();
  decode_errors_.set_callback([this](const std::string& channel, const std::string& reason) {
    count_fault("decode_errors", channel + ": " + reason);
  });
}

BasedNode::~BasedNode() { stop(); }

void BasedNode::drive_circle(const CircleSpec& spec) {
  if (started_) throw std::logic_error("drive_circle() after start()");
  circle_.emplace(spec, params_.command);
}

void BasedNode::start() {
  if (started_) return;
  started_ = true;
  if (!circle_) {
    subscribe<base_cmd_t>(bus_, channels::kBaseCmd, [this](const base_cmd_t& m) {
      handle_command(Velocity{m.vx, m.vy, m.omega});
    }, decode_errors_);
  }
  const BasedParams& p = params_;
  const int64_t now = monotonic_us();
  // A GET or POST blocks at most connect + write + read timeouts; the odometry thread also waits out
  // its reconnect backoff.
  poll_beat_ = beats_.add("odometry",
                          seconds_to_utime(p.connection.backoff_max_s + p.odometry.connect_timeout_s +
                                           2.0 * p.odometry.reply_timeout_s + 1.0 / p.odometry.poll_rate_hz +
                                           kWorkerSlackS),
                          now);
  command_beat_ = beats_.add("command",
                             seconds_to_utime(p.odometry.connect_timeout_s + 2.0 * p.command.reply_timeout_s +
                                              1.0 / p.command.rate_hz + kWorkerSlackS),
                             now);
  status_beat_ = beats_.add("status", seconds_to_utime(1.0 + kWorkerSlackS), now);
  poll_thread_ = std::thread([this] { poll_loop(); });
  command_thread_ = std::thread([this] { command_loop(); });
  status_thread_ = std::thread([this] { status_loop(); });
}

void BasedNode::stop() {
  {
    std::lock_guard<std::mutex> lock(wake_mutex_);
    stopping_ = true;
  }
  wake_.notify_all();
  for (std::thread* t : {&poll_thread_, &command_thread_, &status_thread_}) {
    if (t->joinable()) t->join();
  }
}

std::string BasedNode::check_workers(int64_t now_mono_us) {
  std::string stalled = beats_.stalled(now_mono_us);
  if (!stalled.empty() && !stall_reported_) {
    count_fault("worker_stalls", stalled + "; watchdog keep-alives withheld");
  } else if (stalled.empty() && stall_reported_) {
    based_log(LogLevel::kNotice, "every thread runs again; watchdog keep-alives resume");
  }
  stall_reported_ = !stalled.empty();
  return stalled;
}

bool BasedNode::wait_until(std::chrono::steady_clock::time_point t) {
  std::unique_lock<std::mutex> lock(wake_mutex_);
  return !wake_.wait_until(lock, t, [this] { return stopping_.load(); });
}

void BasedNode::count(const std::string& name, int64_t n) {
  std::lock_guard<std::mutex> lock(mutex_);
  counters_[name] += n;
}

void BasedNode::count_fault(const std::string& counter, const std::string& detail, bool degrades) {
  const int64_t now = monotonic_us();
  std::string line;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    ++counters_[counter];
    if (degrades) health_.fault(counter + ": " + detail, now);
    line = burst_.fault(counter, detail, now);
  }
  if (!line.empty()) based_log(LogLevel::kWarning, line);
}

int64_t BasedNode::counter(const std::string& name) const {
  std::lock_guard<std::mutex> lock(mutex_);
  const auto it = counters_.find(name);
  return it == counters_.end() ? 0 : it->second;
}

Health::Report BasedNode::health() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return health_.report(monotonic_us());
}

void BasedNode::handle_command(const Velocity& v) {
  bool taken = false;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    ++counters_["commands_received"];
    taken = gate_.command(v, monotonic_us());
  }
  // Bad input: counted, logged per burst, and DEGRADED for degraded_hold_s like any other fault.
  if (!taken) count_fault("commands_rejected", "BASE_CMD with a non-finite velocity ignored");
}

// ---- odometry ----

void BasedNode::poll_loop() {
  RobotinoClient client(url_, params_.odometry.connect_timeout_s, params_.odometry.reply_timeout_s);
  OdometryTracker tracker(params_.odometry);
  const auto period = seconds(1.0 / params_.odometry.poll_rate_hz);
  double backoff = params_.connection.backoff_initial_s;
  auto next = std::chrono::steady_clock::now();
  int64_t connections_seen = 0;
  while (!stopping_) {
    beats_.beat(poll_beat_, monotonic_us());
    if (poll_hook_) {
      poll_hook_([this] { return stopping_.load(); });
      if (stopping_) break;
    }
    const Reply reply = client.get(kOdometryPath);
    const int64_t now = monotonic_us();
    if (const int64_t c = client.connections_opened(); c != connections_seen) {
      count("connections_opened", c - connections_seen);
      connections_seen = c;
    }
    if (reply.status == ReplyStatus::kConnectFailed) {
      count_fault("connect_failures", reply.error + ", retrying in " + std::to_string(backoff).substr(0, 4) + " s");
      {
        std::lock_guard<std::mutex> lock(mutex_);
        health_.reachable(false, "cannot connect to " + params_.url + ": " + reply.error, now);
      }
      if (!wait_until(std::chrono::steady_clock::now() + seconds(backoff))) break;
      backoff = std::min(2.0 * backoff, params_.connection.backoff_max_s);
      next = std::chrono::steady_clock::now();
      continue;
    }
    backoff = params_.connection.backoff_initial_s;
    {
      std::lock_guard<std::mutex> lock(mutex_);
      health_.reachable(true, "", now);
    }
    switch (reply.status) {
      case ReplyStatus::kTimeout: count_fault("reply_timeouts", reply.error); break;
      case ReplyStatus::kDropped: count_fault("replies_dropped", reply.error); break;
      case ReplyStatus::kHttpError: count_fault("http_errors", reply.error); break;
      case ReplyStatus::kTooLarge: count_fault("replies_malformed", reply.error); break;
      case ReplyStatus::kConnectFailed: break;  // handled above
      case ReplyStatus::kOk: {
        OdometrySample raw;
        std::string error;
        if (!parse_odometry_reply(reply.body, raw, error)) {
          count_fault("replies_malformed", error);
          break;
        }
        count("replies_ok");
        raw.utime = sample_utime(reply.recv_utime, reply.round_trip_us);      // published
        raw.mono_us = sample_utime(reply.recv_mono_us, reply.round_trip_us);  // timing checks
        const TrackResult r = tracker.track(raw);
        switch (r.kind) {
          // Routine when polling faster than the base samples; only a long run (stale) degrades.
          case SampleKind::kRepeated: count_fault("repeated_seq", r.detail, false); break;
          case SampleKind::kSeqBackwards:
          case SampleKind::kJump:
            count("odometry_resets");
            count_fault(r.kind == SampleKind::kSeqBackwards ? "seq_backwards" : "odometry_jumps",
                        r.detail + (params_.odometry.continuous_after_reset ? "; ODOMETRY continues from the predicted pose"
                                                                            : "; ODOMETRY follows the base's new origin"));
            break;
          default: break;
        }
        if (r.publish) {
          const OdometrySample& s = *r.publish;
          odometry_t m{};
          m.utime = s.utime;
          m.seq = s.seq;
          m.x = s.x;
          m.y = s.y;
          m.theta = s.theta;
          m.vx = s.vx;
          m.vy = s.vy;
          m.omega = s.omega;
          {
            std::lock_guard<std::mutex> lock(publish_mutex_);
            publish(bus_, channels::kOdometry, m);
          }
          std::lock_guard<std::mutex> lock(mutex_);
          ++counters_["odometry_published"];
          ++interval_published_;
          rtt_sum_us_ += reply.round_trip_us;
          rtt_max_us_ = std::max(rtt_max_us_, reply.round_trip_us);
          ++rtt_count_;
          health_.new_sample(now);
          stale_ = false;
        }
        break;
      }
    }
    {
      // Stale: replies come but the base's seq has not moved for stale_after_s. One event per episode.
      // Monotonic: a wall-clock step must neither raise nor hide a stale episode.
      const bool stale_now = tracker.stale(reply.recv_mono_us);
      bool report = false;
      {
        std::lock_guard<std::mutex> lock(mutex_);
        if (stale_now && !stale_) report = true;
        stale_ = stale_ || stale_now;
      }
      if (report) count_fault("stale_events", "no new odometry seq for more than " + std::to_string(params_.odometry.stale_after_s).substr(0, 5) + " s");
    }
    next += period;
    const auto t = std::chrono::steady_clock::now();
    if (next < t - period) next = t;  // fell behind (slow replies): do not fire a burst to catch up
    if (!wait_until(next)) break;
  }
}

// ---- commands ----

void BasedNode::command_loop() {
  RobotinoClient client(url_, params_.odometry.connect_timeout_s, params_.command.reply_timeout_s);
  const auto period = seconds(1.0 / params_.command.rate_hz);
  const int64_t start_us = monotonic_us();
  auto next = std::chrono::steady_clock::now();
  auto retry_after = next;
  double backoff = params_.connection.backoff_initial_s;
  int64_t trips_seen = 0;
  int64_t last_post_ok_us = INT64_MIN;
  while (!stopping_) {
    const int64_t now = monotonic_us();
    beats_.beat(command_beat_, now);
    Velocity out;
    bool circle_done = false;
    {
      std::lock_guard<std::mutex> lock(mutex_);
      if (circle_) {
        const double t = static_cast<double>(now - start_us) * 1e-6;
        gate_.command(circle_->command(t), now);
        circle_done = circle_->finished(t);
      }
      // Commands that did not reach the base (connecting, timeouts) did not move it either, and after
      // kBaseStopsAfterUs without one it stands: ramp from rest, never jump to the gate's last output.
      if (last_post_ok_us == INT64_MIN || now - last_post_ok_us >= kBaseStopsAfterUs) gate_.base_stopped();
      out = gate_.step(now);
      if (gate_.deadman_trips() != trips_seen) {
        counters_["deadman_stops"] += gate_.deadman_trips() - trips_seen;
        trips_seen = gate_.deadman_trips();
        const std::string line = burst_.fault(
            "deadman_stops", "no BASE_CMD for " + std::to_string(params_.command.deadman_s).substr(0, 5) + " s, base stopped", now);
        if (!line.empty()) based_log(LogLevel::kWarning, line);
      }
    }
    if (std::chrono::steady_clock::now() >= retry_after) {
      const Reply r = client.post(kOmnidrivePath, format_omnidrive_command(out.vx, out.vy, out.omega));
      if (r.status == ReplyStatus::kOk) {
        backoff = params_.connection.backoff_initial_s;
        last_post_ok_us = now;
        std::lock_guard<std::mutex> lock(mutex_);
        ++counters_["commands_sent"];
        last_sent_ = out;
      } else {
        count_fault("command_failures", std::string(to_string(r.status)) + ": " + r.error);
        if (r.status == ReplyStatus::kConnectFailed) {
          retry_after = std::chrono::steady_clock::now() + seconds(backoff);
          backoff = std::min(2.0 * backoff, params_.connection.backoff_max_s);
        }
      }
    }
    if (circle_done && out == Velocity{} && !finished_) {
      based_log(LogLevel::kInfo, "circle finished, base stopped");
      finished_ = true;
    }
    next += period;
    const auto t = std::chrono::steady_clock::now();
    if (next < t - period) next = t;
    if (!wait_until(next)) break;
  }
  // Leave the base standing: it would stop by itself after 200 ms, but say so explicitly.
  const Reply r = client.post(kOmnidrivePath, format_omnidrive_command(0.0, 0.0, 0.0));
  if (r.status == ReplyStatus::kOk) {
    std::lock_guard<std::mutex> lock(mutex_);
    ++counters_["commands_sent"];
    last_sent_ = Velocity{};
  } else {
    based_log(LogLevel::kError, "could not send the final zero velocity: " + r.error);
  }
}

// ---- status ----

driver_status_t BasedNode::make_status() {
  driver_status_t s{};
  const int64_t now = monotonic_us();
  std::lock_guard<std::mutex> lock(mutex_);
  s.utime = now_utime();
  s.driver = "based";
  const Health::Report h = health_.report(now);
  s.state = static_cast<int8_t>(h.state);
  s.message = h.message;
  for (const char* name : kCounterNames) {
    s.counter_names.push_back(name);
    const auto it = counters_.find(name);
    s.counter_values.push_back(it == counters_.end() ? 0 : it->second);
  }
  s.counter_names.push_back("lcm_publish_errors");
  s.counter_values.push_back(bus_.publish_errors());
  s.num_counters = static_cast<int32_t>(s.counter_names.size());
  const double interval_s = std::max(1e-6, static_cast<double>(now - interval_start_us_) * 1e-6);
  const auto stat = [&](const char* name, double v) {
    s.stat_names.push_back(name);
    s.stat_values.push_back(v);
  };
  stat("odometry_rate_hz", static_cast<double>(interval_published_) / interval_s);
  stat("round_trip_mean_us", rtt_count_ ? static_cast<double>(rtt_sum_us_) / static_cast<double>(rtt_count_) : 0.0);
  stat("round_trip_max_us", static_cast<double>(rtt_max_us_));
  stat("cmd_vx", last_sent_.vx);
  stat("cmd_vy", last_sent_.vy);
  stat("cmd_omega", last_sent_.omega);
  s.num_stats = static_cast<int32_t>(s.stat_names.size());
  interval_start_us_ = now;
  interval_published_ = 0;
  rtt_sum_us_ = rtt_max_us_ = rtt_count_ = 0;
  return s;
}

void BasedNode::log_lines() {
  std::vector<std::string> lines;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    lines = burst_.flush(monotonic_us());
  }
  for (const std::string& l : lines) based_log(LogLevel::kWarning, l);
}

void BasedNode::status_loop() {
  auto next = std::chrono::steady_clock::now() + std::chrono::seconds(1);
  HealthState last_state = HealthState::kStarting;
  while (wait_until(next)) {
    beats_.beat(status_beat_, monotonic_us());
    next += std::chrono::seconds(1);
    const driver_status_t s = make_status();
    const auto state = static_cast<HealthState>(s.state);
    if (state != last_state) {
      based_log(state == HealthState::kOk || state == HealthState::kStarting ? LogLevel::kNotice : LogLevel::kWarning,
               std::string("state ") + to_string(state) + (s.message.empty() ? "" : ": " + s.message));
      last_state = state;
    }
    {
      std::lock_guard<std::mutex> lock(publish_mutex_);
      publish(bus_, channels::kDriverStatus, s);
    }
    log_lines();
  }
}

}  // namespace whiskeye::based
