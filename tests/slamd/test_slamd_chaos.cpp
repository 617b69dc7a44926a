// The chaos test (docs/reliability.md, "A chaos test"): live slamd over udpm:// (in a private network
// namespace) fed four minutes of simulated data while a fault injector interleaves SIGKILL and
// restart, malformed and oversized messages, a 10x flood, and the state directory filling up and
// being freed. Afterwards slamd is running and OK, every fault was counted in SLAM_STATUS, memory
// stayed bounded, and the map equals, experience for experience and byte for byte, the map of an
// uninterrupted `slamd --replay` fed the same cycles.
//
// What the uninterrupted run is not fed: what slamd could not have kept. The messages published while
// it was down, and, at each SIGKILL, the cycle it was still assembling (its odometry since the last
// cycle handed out, a whisk cycle waiting for its camera frame): held in memory, not yet a cycle, so
// in no checkpoint. Every cycle handed out was checkpointed before the kill (the injector waits for
// the newest checkpoint to hold it), so nothing processed is lost; the test proves that.
#include "whiskeye/slamd/checkpoint_store.h"
#include "whiskeye/slamd/cycle_sync.h"
#include "slamd_files.h"
#include "private_tmpfs.h"
#include "scratch.h"
#include "subprocess.h"

#include "whiskeye/common/bus.h"
#include "whiskeye/common/utime.h"

#include <whiskeye/driver_status_t.hpp>
#include <whiskeye/image_t.hpp>
#include <whiskeye/odometry_t.hpp>
#include <whiskeye/slam_status_t.hpp>
#include <whiskeye/vita_event_t.hpp>
#include <whiskeye/vita_map_t.hpp>
#include <whiskeye/vita_pose_t.hpp>
#include <whiskeye/whisk_cycle_t.hpp>

#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstring>
#include <deque>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <mutex>
#include <optional>
#include <regex>
#include <set>
#include <sstream>
#include <span>
#include <thread>
#include <unistd.h>

namespace whiskeye {
namespace {

namespace fs = std::filesystem;
using testing::Subprocess;
using testing::wait_until;

const std::string kSlamd = SLAMD_EXE;
const std::string kConfig = WHISKEYE_SOURCE_DIR "/config/slam.yaml";

// The schedule, in seconds of data from the start of the log.
constexpr double kDataSeconds = 240.0;
constexpr double kSpeed = 4.0;        // data seconds per wall second (the flood goes at 1x)
constexpr double kDownSeconds = 3.0;  // data published while slamd is down
const std::vector<double> kKillsAt{30, 70, 130, 160, 190, 215};
const std::vector<double> kHostileAt{20, 145};
constexpr double kFloodFrom = 50, kFloodTo = 60;
constexpr int kFloodFactor = 10;  // every message of the flood window goes out 10 times: itself and 9 stale copies
                                  // spread evenly until its channel's next message
constexpr double kDiskFullFrom = 90, kDiskFullTo = 110;
// A burst: this much data sent at once, as a sender catching up after a pause does (75 odometry
// samples, 7 camera frames: ~5 MB, within the 8 MB receive buffers of slamd's socket and the test's).
constexpr double kBurstAt = 120, kBurstSeconds = 1.5;
// Held up longer than this (a busy machine), the injector slips its schedule instead of sending the
// overdue data at once: a burst it did not mean could outgrow a socket's receive buffer (in the
// flood, 0.3 s of data is 9 MB), a loss that is counted but is not one of the faults injected here.
constexpr auto kMaxBehind = std::chrono::milliseconds(100);
constexpr long kMaxRssKb = 256 * 1024;  // slamd's high-water mark, whatever was thrown at it

long vm_hwm_kb(int pid) { return static_cast<long>(testing::proc_status_kb(pid, "VmHWM")); }

// What LCM says (with LCM_DBG=all) it dropped inside a process: a message missing fragments, a
// fragment out of place. The kernel's drops are counted in SLAM_STATUS; these are not.
std::string lcm_internal_drops(const std::string& output) {
  std::string lines;
  std::istringstream in(output);
  for (std::string line; std::getline(in, line);) {
    if (line.find("Dropping message") != std::string::npos || line.find("dropping invalid fragment") != std::string::npos) {
      lines += line + "\n";
    }
  }
  return lines;
}

// The map's cycle count in the newest checkpoint of `dir` (0: none yet).
uint64_t newest_checkpoint_sequence(const fs::path& dir) {
  const std::vector<fs::path> files = testing::checkpoint_files(dir);
  return files.empty() ? 0 : slamd::read_checkpoint(files.back().string()).sequence;
}

// What slamd publishes, gathered by a thread of its own: it must read every datagram on the group
// (camera frames included) to see slamd's few small messages.
class Observer {
 public:
  Observer() {
    subscribe<vita_event_t>(bus_, "VITA_EVENT", [this](const vita_event_t& m) {
      std::lock_guard lock(mutex_);
      ++events_;
      all_events_.push_back(m);
      last_event_utime_ = m.utime;
      last_event_at_ = std::chrono::steady_clock::now();
    }, errors_);
    subscribe<slam_status_t>(bus_, "SLAM_STATUS", [this](const slam_status_t& m) {
      std::lock_guard lock(mutex_);
      status_ = m;
      if (m.state == driver_status_t::STATE_DEGRADED) degraded_ = m;
    }, errors_);
    subscribe<vita_map_t>(bus_, "VITA_MAP", [this](const vita_map_t& m) {
      std::lock_guard lock(mutex_);
      map_ = m;
    }, errors_);
    subscribe<vita_pose_t>(bus_, "VITA_POSE", [this](const vita_pose_t& m) {
      std::lock_guard lock(mutex_);
      poses_.insert(m.utime);
    }, errors_);
    // LCM's own queue would drop what this thread has not handled beyond 30 a channel.
    for (const char* channel : {"VITA_EVENT", "SLAM_STATUS", "VITA_MAP", "VITA_POSE"}) bus_.set_queue_capacity(channel, 0);
    thread_ = std::thread([this] {
      while (!stop_) bus_.handle_timeout(20);
    });
  }
  ~Observer() {
    stop_ = true;
    thread_.join();
  }
  // A new slamd process: its counters start again.
  void new_session() {
    std::lock_guard lock(mutex_);
    session_first_event_.push_back(all_events_.size());
    events_ = 0;
    status_.reset();
    degraded_.reset();
  }
  int events() const {
    std::lock_guard lock(mutex_);
    return events_;
  }
  int64_t last_event_utime() const {
    std::lock_guard lock(mutex_);
    return last_event_utime_;
  }
  double seconds_since_last_event() const {
    std::lock_guard lock(mutex_);
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - last_event_at_).count();
  }
  std::optional<slam_status_t> status() const {
    std::lock_guard lock(mutex_);
    return status_;
  }
  std::optional<slam_status_t> degraded() const {
    std::lock_guard lock(mutex_);
    return degraded_;
  }
  std::optional<vita_map_t> map() const {
    std::lock_guard lock(mutex_);
    return map_;
  }
  int64_t decode_errors() const { return errors_.total(); }
  std::vector<vita_event_t> all_events() const {
    std::lock_guard lock(mutex_);
    return all_events_;
  }
  // The ends of session `s`'s first and last cycles (nullopt: it handed out none).
  std::optional<std::pair<int64_t, int64_t>> cycle_ends(int s) const {
    std::lock_guard lock(mutex_);
    const std::size_t at = session_first_event_.at(static_cast<std::size_t>(s));
    const std::size_t next = static_cast<std::size_t>(s) + 1 < session_first_event_.size()
                                 ? session_first_event_[static_cast<std::size_t>(s) + 1]
                                 : all_events_.size();
    if (at >= next) return std::nullopt;
    return std::make_pair(all_events_[at].utime, all_events_[next - 1].utime);
  }
  // Whether slamd published a VITA_POSE for the odometry sample of time `utime`.
  bool has_pose(int64_t utime) const {
    std::lock_guard lock(mutex_);
    return poses_.count(utime) != 0;
  }

 private:
  LcmBus bus_;
  DecodeErrors errors_;
  mutable std::mutex mutex_;
  int events_ = 0;
  std::vector<vita_event_t> all_events_;  // every session's
  std::vector<std::size_t> session_first_event_;  // per session: its first event's index in all_events_
  std::set<int64_t> poses_;                       // every VITA_POSE's time (its odometry sample's)
  int64_t last_event_utime_ = INT64_MIN;
  std::chrono::steady_clock::time_point last_event_at_ = std::chrono::steady_clock::now();
  std::optional<slam_status_t> status_;
  std::optional<slam_status_t> degraded_;
  std::optional<vita_map_t> map_;
  std::atomic<bool> stop_{false};
  std::thread thread_;
};

// One of slamd's inputs in the simulator's log, and whether the uninterrupted run is fed it.
struct Input {
  int64_t event_utime = 0;  // the log's time: what publishing is paced by
  int64_t sample_utime = 0; // the message's own time (odometry: sample; whisk cycle: its end)
  std::string channel;
  std::span<const uint8_t> data;
  int session = -1;  // the slamd process it was published to; -1: published while slamd was down
  bool kept = true;
};

// Malformed and oversized messages, each of which slamd must reject and count, at data time `now`.
// Returns how many are undecodable and how many decode but are rejected.
std::pair<int, int> publish_hostile(LcmBus& bus, int64_t now) {
  int undecodable = 0, rejected = 0;
  const std::vector<uint8_t> garbage{0xde, 0xad, 0xbe, 0xef, 0x00, 0x01, 0x02, 0x03, 0x04, 0x05, 0x06, 0x07};
  for (const char* channel : {"WHISK_CYCLE", "CAMERA", "ODOMETRY"}) {
    bus.publish_raw(channel, garbage);
    ++undecodable;
  }
  odometry_t odo{};
  odo.utime = now;
  odo.vx = std::numeric_limits<double>::quiet_NaN();
  publish(bus, "ODOMETRY", odo);
  ++rejected;

  whisk_cycle_t wc{};
  wc.utime = wc.utime_start = wc.utime_end = now;
  wc.num_whiskers = 24;
  wc.num_samples = 1;
  wc.sample_utime = {now};
  wc.sample_valid = {1};
  wc.phase = {0};
  wc.theta = {std::vector<float>(24, 7.0f)};  // beyond ±pi
  wc.deflection_x = wc.deflection_y = {std::vector<float>(24, 0.0f)};
  wc.contact = {std::vector<int8_t>(24, 0)};
  publish(bus, "WHISK_CYCLE", wc);
  ++rejected;

  image_t im{};
  im.utime = now;
  im.width = 640;
  im.height = 480;
  im.row_stride = 1280;
  im.pixelformat = image_t::PIXEL_FORMAT_YUYV;
  im.size = 16;
  im.data.assign(16, 0);  // far fewer bytes than row_stride × height
  publish(bus, "CAMERA", im);
  ++rejected;

  // Oversized: 0 whiskers and 200,000 samples (2 MB; ten times the samples a cycle may hold), outside
  // the contract before decoding.
  whisk_cycle_t big{};
  big.utime = big.utime_start = big.utime_end = now;
  big.num_whiskers = 0;
  big.num_samples = 200'000;
  big.sample_utime.assign(static_cast<std::size_t>(big.num_samples), now);
  big.sample_valid.assign(static_cast<std::size_t>(big.num_samples), 1);
  big.phase.assign(static_cast<std::size_t>(big.num_samples), 0);
  big.theta = big.deflection_x = big.deflection_y =
      std::vector<std::vector<float>>(static_cast<std::size_t>(big.num_samples));
  big.contact = std::vector<std::vector<int8_t>>(static_cast<std::size_t>(big.num_samples));
  publish(bus, "WHISK_CYCLE", big);
  ++rejected;
  return {undecodable, rejected};
}

// The chaos run, step by step. Each step asserts what it can see; the test runs them in order, and
// stops at a step's fatal failure. One run: the steps share four minutes of live data, which a test
// each would repeat.
class SlamdChaos : public ::testing::Test {
 protected:
  ~SlamdChaos() override {
    slamd_.reset();  // before its state directory's tmpfs goes
    tmpfs_.reset();
  }

  // The state directory on a small tmpfs of its own, small enough to fill; before any thread exists.
  void mount_state_directory() {
    dir_ = testing::scratch_dir("slamd_chaos");
    state_ = dir_ / "state";
    tmpfs_ = std::make_unique<testing::PrivateTmpfs>(state_.string(), "4m");
    ASSERT_TRUE(tmpfs_->mounted()) << tmpfs_->error();
  }

  // Four minutes of simulated data, and slamd's inputs in it (odometry, whisk cycles, camera frames).
  void simulate_inputs() {
    const std::string sim_log = (dir_ / "sim.lcmlog").string();
    {
      Subprocess sim({VITA_SIM_EXE, "--world", WHISKEYE_SOURCE_DIR "/config/worlds/aliased_arena.yaml", "--robot",
                      WHISKEYE_SOURCE_DIR "/config/robot.yaml", "--duration", std::to_string(kDataSeconds), "--seed",
                      "11", "--quiet", "--output", sim_log});
      ASSERT_EQ(sim.wait(120), 0) << sim.output();
    }
    reader_ = std::make_unique<LogReader>(sim_log);
    LogReader::EventView ev;
    while (reader_->next(ev)) {
      Input in;
      in.channel = std::string(ev.channel);
      if (in.channel == "ODOMETRY") {
        odometry_t m;
        ASSERT_TRUE(decode_message(ev.data, m));
        in.sample_utime = m.utime;
      } else if (in.channel == "WHISK_CYCLE") {
        whisk_cycle_t m;
        ASSERT_TRUE(decode_message(ev.data, m));
        in.sample_utime = m.utime_end;
      } else if (in.channel == "CAMERA") {
        in.sample_utime = ev.utime;
      } else {
        continue;
      }
      in.event_utime = ev.utime;
      in.data = ev.data;  // a view into the mapped log, valid while `reader_` lives
      inputs_.push_back(std::move(in));
    }
    ASSERT_GT(inputs_.size(), 10000u);
    t0_ = inputs_.front().event_utime;
    observer_ = std::make_unique<Observer>();
    bus_ = std::make_unique<LcmBus>();
  }

  // A new session: slamd started on the state directory, resuming after every cycle it handed out.
  void start_slamd() {
    observer_->new_session();
    // LCM_DBG=all: LCM's own lines (quiet in normal traffic) name a message it drops inside slamd.
    slamd_ = std::make_unique<Subprocess>(std::vector<std::string>{kSlamd, "--config", kConfig, "--state-dir", state_.string()},
                                          (dir_ / ("slamd-" + std::to_string(session_) + ".log")).string(),
                                          std::vector<std::string>{"LCM_DBG=all"});
    ASSERT_TRUE(wait_until([&] { return slamd_->output().find("running in vita mode") != std::string::npos; }, 20))
        << slamd_->output();
    const std::string out = slamd_->output();
    if (session_ == 0) {
      EXPECT_EQ(out.find("resuming from"), std::string::npos) << out;
      return;
    }
    std::smatch m;
    ASSERT_TRUE(std::regex_search(out, m, std::regex(R"(resuming from \S+ \(after cycle (\d+)\))"))) << out;
    EXPECT_EQ(std::stoull(m[1]), resumed_after_) << "every cycle handed out before the kill was in the newest checkpoint";
  }

  // Publishes every input in time, paced, with the faults of the schedule between them: the kills
  // (with the session's checks before each), the hostile messages, the full disk, the flood and the burst.
  void publish_with_faults() {
    std::size_t kill = 0;
    bool disk_full = false;
    bool flooding = false;
    bool bursting = false;
    std::map<std::string, std::deque<std::span<const uint8_t>>> recent;  // per channel, for the flood's stale copies
    std::multimap<int64_t, std::pair<std::string, std::span<const uint8_t>>> stale_due;  // by log time
    // The log time of the next message on the same channel (a stale copy goes out before it).
    std::vector<int64_t> next_on_channel(inputs_.size(), INT64_MAX);
    {
      std::map<std::string, int64_t> next;
      for (std::size_t j = inputs_.size(); j-- > 0;) {
        const auto it = next.find(inputs_[j].channel);
        next_on_channel[j] = it == next.end() ? inputs_[j].event_utime + 1'000'000 : it->second;
        next[inputs_[j].channel] = inputs_[j].event_utime;
      }
    }
    const fs::path filler = state_ / "filler";
    restart_pacing(t0_);

    for (std::size_t i = 0; i < inputs_.size(); ++i) {
      if (kill < kKillsAt.size() && inputs_[i].event_utime >= at(kKillsAt[kill])) {
        ASSERT_NO_FATAL_FAILURE(check_session_before_kill());
        ASSERT_NO_FATAL_FAILURE(kill_and_restart(i));
        ++kill;
        if (i >= inputs_.size()) break;
        restart_pacing(inputs_[i].event_utime);
      }
      Input& cur = inputs_[i];
      if (hostile_ < kHostileAt.size() && cur.event_utime >= at(kHostileAt[hostile_])) {
        const auto [u, r] = publish_hostile(*bus_, cur.event_utime);
        hostile_undecodable_ += u;
        hostile_rejected_ += r;
        ++hostile_;
      }
      if (!disk_full && !disk_freed_ && cur.event_utime >= at(kDiskFullFrom) && cur.event_utime < at(kDiskFullTo)) {
        ASSERT_GT(testing::fill_disk(filler.string()), 0u);
        disk_full = true;
      }
      if (disk_full && cur.event_utime >= at(kDiskFullTo)) {
        // While full: DEGRADED, saying why, and the checkpoints counted as failing.
        ASSERT_TRUE(wait_until([&] { return observer_->degraded().has_value(); }, 10)) << slamd_->output();
        const slam_status_t d = *observer_->degraded();
        EXPECT_NE(d.message.find("checkpoints failing, the map is not being saved"), std::string::npos) << d.message;
        EXPECT_GT(d.checkpoint_errors, 0);
        fs::remove(filler);  // OK again by itself: checked at the end of the session
        disk_full = false;
        disk_freed_ = true;
        written_while_full_ = d.checkpoints_written;
        restart_pacing(cur.event_utime);
      }
      const bool flood = cur.event_utime >= at(kFloodFrom) && cur.event_utime < at(kFloodTo);
      if (flood != flooding) {  // the flood goes at 1x, the rest at kSpeed
        restart_pacing(cur.event_utime);
        flooding = flood;
      }
      // The flood's stale copies due before this message.
      while (!stale_due.empty() && stale_due.begin()->first < cur.event_utime) {
        pace(stale_due.begin()->first, flood ? 1.0 : kSpeed);
        bus_->publish_raw(stale_due.begin()->second.first, stale_due.begin()->second.second);
        ++stale_published_;
        stale_due.erase(stale_due.begin());
      }
      // The burst: its messages without pacing, then the schedule goes on from the next one.
      const bool burst = cur.event_utime >= at(kBurstAt) && cur.event_utime < at(kBurstAt + kBurstSeconds);
      if (burst) {
        ++burst_published_;
        bursting = true;
      } else {
        if (bursting) restart_pacing(cur.event_utime);
        bursting = false;
        pace(cur.event_utime, flood ? 1.0 : kSpeed);
      }
      bus_->publish_raw(cur.channel, cur.data);
      cur.session = session_;
      auto& ring = recent[cur.channel];
      if (flood && !ring.empty()) {
        // Nine stale copies, spread evenly until the channel's next message: each older than what its
        // input already delivered, so each is dropped and counted.
        const int64_t period = next_on_channel[i] - cur.event_utime;
        for (int c = 1; c < kFloodFactor; ++c) {
          stale_due.emplace(cur.event_utime + period * c / kFloodFactor,
                            std::make_pair(cur.channel, ring[static_cast<std::size_t>(c - 1) % ring.size()]));
        }
      }
      ring.push_front(cur.data);
      if (ring.size() > kFloodFactor) ring.pop_back();
    }
    EXPECT_GE(kills_, 5);
    EXPECT_EQ(hostile_, kHostileAt.size());
  }

  // Before a kill: this session's faults are all counted, it is OK (or DEGRADED for rejected input),
  // nothing was lost on the way in, and its memory is bounded.
  void check_session_before_kill() {
    ASSERT_NO_FATAL_FAILURE(quiesce());
    const slam_status_t st = settled_status();
    // DEGRADED for 10 s after rejected input, saying so; otherwise OK.
    if (st.state == driver_status_t::STATE_DEGRADED && hostile_undecodable_ + hostile_rejected_ + stale_published_ > 0) {
      EXPECT_NE(st.message.find("rejected input"), std::string::npos) << st.message;
    } else {
      EXPECT_EQ(st.state, driver_status_t::STATE_OK) << st.message;
    }
    if (disk_freed_) {
      EXPECT_GT(st.checkpoints_written, written_while_full_) << "checkpoints again once the disk had room";
    }
    EXPECT_EQ(st.decode_errors, hostile_undecodable_);
    EXPECT_EQ(st.validation_errors, hostile_rejected_ + stale_published_);
    EXPECT_EQ(st.out_of_order, stale_published_);
    EXPECT_EQ(st.lcm_receive_drops, 0) << "session " << session_;
    EXPECT_EQ(st.input_gaps, 0) << "session " << session_ << ": input lost on the way";
    EXPECT_EQ(st.checkpoint_errors > 0, disk_freed_) << "checkpoints failed only while the disk was full";
    max_rss_kb_ = std::max(max_rss_kb_, vm_hwm_kb(slamd_->pid()));
    EXPECT_EQ(lcm_internal_drops(slamd_->output()), "") << "session " << session_;
  }

  // SIGKILL at input `i`; the inputs published while slamd is down (from `i` on, which ends at the
  // first input of the next session); then the next session.
  void kill_and_restart(std::size_t& i) {
    // The cycle being assembled is lost with the process (not in the uninterrupted run).
    const int64_t last_cycle_end = observer_->last_event_utime();
    for (std::size_t j = 0; j < i; ++j) {
      Input& p = inputs_[j];
      if (p.session == session_ && p.channel != "CAMERA" && p.sample_utime > last_cycle_end) p.kept = false;
    }
    resumed_after_ += static_cast<uint64_t>(observer_->events());
    slamd_->signal(SIGKILL);
    ASSERT_EQ(slamd_->wait(10), 128 + SIGKILL);
    ++kills_;
    // Published while slamd is down: lost to it.
    const int64_t down_until = inputs_[i].event_utime + static_cast<int64_t>(kDownSeconds * 1e6);
    restart_pacing(inputs_[i].event_utime);
    for (; i < inputs_.size() && inputs_[i].event_utime < down_until; ++i) {
      pace(inputs_[i].event_utime, kSpeed);
      bus_->publish_raw(inputs_[i].channel, inputs_[i].data);
      inputs_[i].kept = false;
    }
    ++session_;
    hostile_undecodable_ = hostile_rejected_ = 0;
    stale_published_ = 0;
    disk_freed_ = false;
    ASSERT_NO_FATAL_FAILURE(start_slamd());
  }

  // After the last message: running, OK, everything counted; then stopped, which saves the state.
  void check_last_session_and_stop() {
    ASSERT_NO_FATAL_FAILURE(quiesce());
    ASSERT_TRUE(slamd_->running()) << slamd_->output();
    // OK again once the last rejected input is 10 s old.
    std::optional<slam_status_t> last;
    EXPECT_TRUE(wait_until([&] {
      last = observer_->status();
      return last && last->state == driver_status_t::STATE_OK;
    }, 15)) << (last ? last->message : "no SLAM_STATUS");
    const slam_status_t st = settled_status();
    EXPECT_EQ(st.decode_errors, hostile_undecodable_);
    EXPECT_EQ(st.validation_errors, hostile_rejected_ + stale_published_);
    EXPECT_EQ(st.lcm_receive_drops, 0);
    EXPECT_EQ(st.input_gaps, 0);
    max_rss_kb_ = std::max(max_rss_kb_, vm_hwm_kb(slamd_->pid()));
    EXPECT_EQ(lcm_internal_drops(slamd_->output()), "");
    EXPECT_EQ(slamd_->stop(20, SIGTERM), 0) << slamd_->output();
    wait_until([&] { return observer_->seconds_since_last_event() > 0.5; }, 5);  // the last cycle's, flushed at exit
    const uint64_t live_cycles = newest_checkpoint_sequence(state_);
    std::printf("chaos: %d kills, %d sessions, %llu cycles kept, slamd's max RSS %ld kB, a burst of %d messages; the "
                "injector at most %lld ms behind its schedule, which slipped %d times\n",
                kills_, session_ + 1, static_cast<unsigned long long>(live_cycles), max_rss_kb_, burst_published_,
                static_cast<long long>(std::chrono::duration_cast<std::chrono::milliseconds>(max_behind_).count()),
                slipped_);
    EXPECT_GT(burst_published_, 80);
    EXPECT_LE(max_rss_kb_, kMaxRssKb);
    EXPECT_EQ(observer_->decode_errors(), 0);
  }

  // Nothing slamd was sent was lost on the way in (LCM drops without a trace what its queue cannot
  // hold): every odometry sample that the uninterrupted run is fed, from the one at which the
  // session's first cycle had surely been handed out (max_wait_s after its end; before it a sample
  // gives no pose) to the session's last cycle, gave a VITA_POSE.
  void check_every_kept_odometry_sample_gave_a_pose() {
    const int64_t max_wait_us = seconds_to_utime(slamd::SyncParams{}.max_wait_s);  // the shipped config's
    for (int s = 0; s <= session_; ++s) {
      const auto cycles = observer_->cycle_ends(s);
      ASSERT_TRUE(cycles) << "session " << s << " handed out no cycle";
      int missing = 0, sent = 0;
      int64_t first_missing = 0;
      for (const Input& in : inputs_) {
        if (in.session != s || !in.kept || in.channel != "ODOMETRY") continue;
        if (in.sample_utime <= cycles->first + max_wait_us || in.sample_utime > cycles->second) continue;
        ++sent;
        if (observer_->has_pose(in.sample_utime)) continue;
        if (missing++ == 0) first_missing = in.sample_utime;
      }
      EXPECT_EQ(missing, 0) << "session " << s << ": " << missing << " of " << sent
                            << " odometry samples gave no VITA_POSE, the first at data time "
                            << static_cast<double>(first_missing - t0_) * 1e-6 << " s";
    }
  }

  // The uninterrupted run: `slamd --replay` of the kept inputs, on a state directory of its own.
  void replay_uninterrupted() {
    const std::string kept_log = (dir_ / "kept.lcmlog").string();
    int kept = 0;
    {
      LogWriterBus writer(kept_log);
      for (const Input& in : inputs_) {
        if (!in.kept) continue;
        writer.set_time(in.event_utime);
        writer.publish_raw(in.channel, in.data);
        ++kept;
      }
    }
    EXPECT_LT(kept, static_cast<int>(inputs_.size()));
    reference_state_ = dir_ / "reference_state";
    reference_out_ = (dir_ / "reference.lcmlog").string();
    Subprocess replay({kSlamd, "--replay", kept_log, "--output", reference_out_, "--config", kConfig, "--state-dir",
                       reference_state_.string()});
    ASSERT_EQ(replay.wait(120), 0) << replay.output();
  }

  // The live map equals the uninterrupted run's: event for event, experience for experience, and the
  // saved state byte for byte.
  void check_map_equals_the_uninterrupted_runs() {
    const std::vector<fs::path> live_files = testing::checkpoint_files(state_);
    const std::vector<fs::path> reference_files = testing::checkpoint_files(reference_state_);
    ASSERT_FALSE(live_files.empty());
    ASSERT_FALSE(reference_files.empty());
    const slamd::Checkpoint live = slamd::read_checkpoint(live_files.back().string());
    const slamd::Checkpoint reference = slamd::read_checkpoint(reference_files.back().string());
    EXPECT_EQ(live.sequence, reference.sequence) << "cycles in the map";

    // Cycle for cycle: what each did to the map (every cycle handed out live was kept, so the two
    // runs handed out the same cycles).
    const testing::SlamdOutput reference_output = testing::read_slamd_output(reference_out_);
    const std::vector<vita_event_t>& reference_events = reference_output.events;
    const std::optional<vita_map_t> reference_map =
        reference_output.maps.empty() ? std::nullopt : std::optional<vita_map_t>(reference_output.maps.back());
    const std::vector<vita_event_t> live_events = observer_->all_events();
    EXPECT_EQ(live_events.size(), reference_events.size());
    for (std::size_t e = 0; e < std::min(live_events.size(), reference_events.size()); ++e) {
      const vita_event_t& a = live_events[e];
      const vita_event_t& b = reference_events[e];
      if (a.cycle != b.cycle || a.type != b.type || a.from_id != b.from_id || a.to_id != b.to_id ||
          a.template_id != b.template_id) {
        ADD_FAILURE() << "event " << e << " differs: live cycle " << a.cycle << " (t " << a.utime << ") type "
                      << int(a.type) << " " << a.from_id << "->" << a.to_id << " template " << a.template_id
                      << "; uninterrupted cycle " << b.cycle << " (t " << b.utime << ") type " << int(b.type) << " "
                      << b.from_id << "->" << b.to_id << " template " << b.template_id;
        break;
      }
    }
    // Experience for experience: the last VITA_MAP of each.
    const std::optional<vita_map_t> live_map = observer_->map();
    ASSERT_TRUE(reference_map && live_map);
    EXPECT_EQ(live_map->num_experiences, reference_map->num_experiences);
    for (int e = 0; e < std::min(live_map->num_experiences, reference_map->num_experiences); ++e) {
      const experience_t& a = live_map->experiences[static_cast<std::size_t>(e)];
      const experience_t& b = reference_map->experiences[static_cast<std::size_t>(e)];
      EXPECT_EQ(a.id, b.id) << e;
      EXPECT_EQ(a.x, b.x) << e;
      EXPECT_EQ(a.y, b.y) << e;
      EXPECT_EQ(a.theta, b.theta) << e;
      EXPECT_EQ(a.utime_created, b.utime_created) << e;
      EXPECT_EQ(a.visual_template_id, b.visual_template_id) << e;
      EXPECT_EQ(a.tactile_template_id, b.tactile_template_id) << e;
      EXPECT_EQ(a.dense, b.dense) << e;
    }
    EXPECT_EQ(live_map->num_links, reference_map->num_links);
    EXPECT_EQ(live_map->current_experience_id, reference_map->current_experience_id);
    // And the whole state, byte for byte: templates, pose cells, links and all.
    if (live.payload != reference.payload) {
      std::size_t first = 0;
      while (first < std::min(live.payload.size(), reference.payload.size()) &&
             live.payload[first] == reference.payload[first]) {
        ++first;
      }
      ADD_FAILURE() << "the saved states differ (" << live.payload.size() << " vs " << reference.payload.size()
                    << " bytes, first at byte " << first << " of the payload)";
    }
  }

  // After a failure, kept for a look: every session's slamd log, both final states (those there
  // are), the reference replay's output.
  void keep_for_a_look() {
    const fs::path keep = fs::path(::testing::TempDir()) / ("slamd_chaos_failure_" + std::to_string(::getpid()));
    fs::create_directories(keep);
    for (const auto& e : fs::directory_iterator(dir_)) {
      if (e.path().extension() == ".log" || e.path().filename() == "reference.lcmlog") fs::copy(e.path(), keep);
    }
    const std::vector<fs::path> live_files = testing::checkpoint_files(state_);
    if (!live_files.empty()) fs::copy(live_files.back(), keep / "live.vslam");
    if (!reference_state_.empty() && fs::exists(reference_state_)) {
      const std::vector<fs::path> reference_files = testing::checkpoint_files(reference_state_);
      if (!reference_files.empty()) fs::copy(reference_files.back(), keep / "reference.vslam");
    }
    std::printf("chaos: slamd's logs, both final states and the reference output kept in %s\n", keep.c_str());
  }

 private:
  int64_t at(double seconds) const { return t0_ + static_cast<int64_t>(seconds * 1e6); }

  // Until every cycle slamd handed out is in the newest checkpoint and nothing more comes.
  void quiesce() {
    ASSERT_TRUE(wait_until([&] {
      return observer_->seconds_since_last_event() > 0.5 &&
             newest_checkpoint_sequence(state_) == resumed_after_ + static_cast<uint64_t>(observer_->events());
    }, 30)) << "events " << observer_->events() << " after cycle " << resumed_after_ << ", newest checkpoint after cycle "
            << newest_checkpoint_sequence(state_) << "\n" << slamd_->output();
  }

  // The newest SLAM_STATUS of this session, once it has counted every cycle handed out.
  slam_status_t settled_status() {
    std::optional<slam_status_t> st;
    EXPECT_TRUE(wait_until([&] {
      st = observer_->status();
      return st && st->cycles == observer_->events();
    }, 5)) << slamd_->output();
    return st.value_or(slam_status_t{});
  }

  void restart_pacing(int64_t event_utime) {
    pace_start_ = std::chrono::steady_clock::now();
    pace_utime_ = event_utime;
  }

  // Sleeps until `event_utime` is due at `speed` data seconds per wall second. How far, and how often
  // beyond kMaxBehind, the injector fell behind its schedule (a busy machine, the hostile messages'
  // 2 MB) is recorded. Up to kMaxBehind it sends what is overdue at once: a burst slamd must take
  // whole (LCM's queue of 30 unhandled messages lost odometry at 40).
  void pace(int64_t event_utime, double speed) {
    const auto due = pace_start_ + std::chrono::microseconds(static_cast<int64_t>((event_utime - pace_utime_) / speed));
    const auto behind = std::chrono::steady_clock::now() - due;
    max_behind_ = std::max(max_behind_, behind);
    if (behind > kMaxBehind) {
      restart_pacing(event_utime);
      ++slipped_;
      return;
    }
    std::this_thread::sleep_until(due);
  }

  fs::path dir_;
  fs::path state_;  // slamd's state directory, on its own tmpfs
  std::unique_ptr<testing::PrivateTmpfs> tmpfs_;
  std::unique_ptr<LogReader> reader_;  // the simulated log, mapped: the inputs' data are views into it
  std::vector<Input> inputs_;
  int64_t t0_ = 0;  // the first input's log time
  std::unique_ptr<Observer> observer_;
  std::unique_ptr<LcmBus> bus_;
  std::unique_ptr<Subprocess> slamd_;  // the current session's
  int session_ = 0;
  uint64_t resumed_after_ = 0;  // the checkpointed cycles the current session started from
  long max_rss_kb_ = 0;
  // This session's faults.
  int hostile_undecodable_ = 0;
  int hostile_rejected_ = 0;
  int64_t stale_published_ = 0;
  bool disk_freed_ = false;
  int64_t written_while_full_ = 0;
  // The whole run's.
  int kills_ = 0;
  std::size_t hostile_ = 0;
  int burst_published_ = 0;
  // Pacing.
  std::chrono::steady_clock::time_point pace_start_;
  int64_t pace_utime_ = 0;
  std::chrono::steady_clock::duration max_behind_{};
  int slipped_ = 0;
  // The uninterrupted run's.
  fs::path reference_state_;
  std::string reference_out_;
};

TEST_F(SlamdChaos, SurvivesKillsHostileMessagesAFloodAndAFullDiskAndKeepsTheMapOfAnUninterruptedRun) {
  ASSERT_NO_FATAL_FAILURE(mount_state_directory());
  ASSERT_NO_FATAL_FAILURE(simulate_inputs());
  // Each step runs while no step before it failed fatally; after any failure the files are kept.
  start_slamd();
  if (!HasFatalFailure()) publish_with_faults();
  if (!HasFatalFailure()) check_last_session_and_stop();
  if (!HasFatalFailure()) check_every_kept_odometry_sample_gave_a_pose();
  if (!HasFatalFailure()) replay_uninterrupted();
  if (!HasFatalFailure()) check_map_equals_the_uninterrupted_runs();
  if (HasFailure()) keep_for_a_look();
}

}  // namespace
}  // namespace whiskeye
