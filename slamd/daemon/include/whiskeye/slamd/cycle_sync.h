// Gathers what one SLAM cycle needs: a completed whisk cycle, the camera frame nearest its end
// (within a tolerance), and the odometry since the previous cycle.
//
// Decisions depend only on the messages' own sample times, never on the wall clock, so a live run
// (lcm-logplayer into slamd) and `slamd --replay` of the same log take the same decisions:
//   - a cycle ending at E waits until a camera frame at or after E + tolerance has arrived (no
//     closer frame can still come), or until data time reaches E + max_wait (camera missing);
//   - and until odometry has reached E (or data time E + max_wait).
// Data time = the newest sample time seen on any input channel.
//
// Sample times are checked on the way in; each add_*() returns "" or why the message was dropped
// (the node counts and logs it): older than what that input already delivered (out of order), or
// more than max_jump_s past data time. The latter is one bad timestamp (dropping it keeps one
// message from stalling every cycle behind it, or from ending the run early) until the jump is
// confirmed — by a second input, or by the same input's next samples while every other input is
// silent (kConfirmSamples in a row, each in line with the one before, over kConfirmSpanUs: whisking
// resumed after a pause, a clock step forward, a new recording) — and then followed. A clock stepped
// *back* is followed the same way: samples more than max_jump_s older than data time (and than
// what their input delivered) are dropped until confirmed, then pending cycles are handed out as
// complete as they are and the synchroniser starts over on the new time line. Any sample taken in
// line with data time (a late one is not taken) cancels a step awaiting confirmation, so one input
// with a wrong clock never takes data time from inputs that are still running. A corrupt time that
// could not be checked (an input's first sample) is undone the same way: when an input's newest
// time lies more than max_jump_s past every other input's and kConfirmSamples of its samples in a
// row agree with the others, that time (and what was buffered at it) is dropped and the input goes
// on from its new samples.
#pragma once

#include "whiskeye/common/message_layout.h"  // CameraFrame: a frame as the synchroniser keeps it

#include <whiskeye/image_t.hpp>
#include <whiskeye/odometry_t.hpp>
#include <whiskeye/whisk_cycle_t.hpp>

#include <cstdint>
#include <deque>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <vector>

namespace whiskeye::slamd {

struct SyncParams {
  double camera_tolerance_s = 0.15;  // a frame farther than this from the cycle's end is not used
  double max_wait_s = 1.0;           // data time to wait for a late or missing camera / odometry
  // Frames kept: the camera's last camera_buffer_s (a whisk cycle arriving up to that late, less the
  // tolerance, finds its frame) and those near the end of a cycle still waiting (for odometry: up to
  // max_wait_s); at most camera_buffer of them (memory), the oldest dropped first and counted.
  double camera_buffer_s = 3.0;
  int camera_buffer = 128;
  double max_jump_s = 10.0;          // a sample time this far past data time waits for confirmation
  int odometry_buffer = 180000;      // samples kept while no whisk cycle comes (1 h at 50 Hz); oldest dropped
  bool operator==(const SyncParams&) const = default;
};

struct SyncedCycle {
  whisk_cycle_t whisk;
  std::optional<CameraFrame> image;    // nearest frame within tolerance, if any
  std::vector<odometry_t> odometry;    // samples with previous end < utime <= this end, time order
};

struct SyncCounters {
  int64_t cycles_without_camera = 0;
  int64_t out_of_order = 0;            // messages older than what was already consumed: dropped
  int64_t time_jumps = 0;              // messages too far from data time (ahead, or behind: a step back), dropped
  int64_t jumps_followed = 0;          // jumps (forward or back) confirmed and followed
  int64_t outliers_dropped = 0;        // an input's corrupt newest time undone (and what it buffered at it)
  int64_t odometry_overflow = 0;       // oldest samples dropped from a full buffer (no whisk cycles)
  int64_t camera_overflow = 0;         // frames within camera_buffer_s (or a waiting cycle's) dropped: buffer full
  bool operator==(const SyncCounters&) const = default;
};

class CycleSynchroniser {
 public:
  // Samples in a row, on one input, that confirm that input's own jump or undo its corrupt time.
  static constexpr int kConfirmSamples = 3;
  // Time those samples must span for one input alone to confirm its jump: longer than any input's
  // period (whisk cycles come about once a second), so that an input still running is heard first.
  static constexpr int64_t kConfirmSpanUs = 2'000'000;

  explicit CycleSynchroniser(const SyncParams& params);

  // Each returns "" when the message was taken, else why it was dropped.
  std::string add_camera(CameraFrame frame);
  std::string add_camera(const image_t& image) { return add_camera(camera_frame(image)); }
  std::string add_odometry(const odometry_t& odometry);
  std::string add_whisk_cycle(whisk_cycle_t cycle);

  // Cycles whose inputs are complete, oldest first.
  std::vector<SyncedCycle> take_ready();
  // Everything pending, as complete as it can be (end of a log).
  std::vector<SyncedCycle> flush();

  const SyncCounters& counters() const { return counters_; }
  std::size_t buffered_frames() const { return frames_.size(); }
  int64_t data_time() const { return data_time_; }

 private:
  bool ready(const whisk_cycle_t& cycle) const;
  SyncedCycle assemble(whisk_cycle_t&& cycle);
  void advance_data_time(int64_t utime);
  // A sample time far from data time, awaiting confirmation that the clock (or the recording) moved.
  struct Step {
    int input = -1;     // the input that stepped; -1: none
    int64_t first = 0;  // its first sample time on the new time line
    int64_t last = 0;   // its newest
    int samples = 0;    // its samples in a row, each in line with the one before
  };
  // "" if `utime` on input `input` (0 camera, 1 odometry, 2 whisk) may advance data time.
  std::string check_jump(int input, int64_t utime, const char* name);
  // For a sample older than what its input delivered: "" when it confirmed a clock stepped back (the
  // synchroniser has started over and the sample is to be taken), else why it was dropped (late:
  // out of order; far behind data time: a step back awaiting confirmation).
  std::string check_step_back(int input, int64_t utime, int64_t own_newest, const char* name);
  // True when `utime` from `input` confirms `step` (a second input near it, or the same input going
  // on alone for kConfirmSamples over kConfirmSpanUs); otherwise `step` follows it.
  bool confirms(Step& step, int input, int64_t utime);
  // Hands the pending cycles out at the next take_ready() and forgets the old time line.
  void restart_time_line();
  // True when `utime`, older than what `input` delivered (`own_newest`), is the kConfirmSamples-th
  // sample in a row that agrees with the other inputs while `own_newest` lies far past all of them.
  bool own_time_was_corrupt(int input, int64_t utime, int64_t own_newest);
  // The newest time the other inputs delivered (INT64_MIN if none).
  int64_t others_newest(int input) const;
  // End of the newest whisk cycle taken: the last pending one, else the last handed out.
  int64_t last_cycle_end() const { return pending_.empty() ? consumed_until_ : pending_.back().utime_end; }
  // Drops the frames older than camera_buffer_s that no waiting cycle can use, then (counted) the
  // oldest beyond camera_buffer.
  void evict_frames();
  // After an input's buffered samples were dropped: data time from what every input still holds.
  void recompute_data_time();

  SyncParams params_;
  std::deque<CameraFrame> frames_;
  std::deque<odometry_t> odometry_;
  std::deque<whisk_cycle_t> pending_;
  int64_t data_time_ = INT64_MIN;
  int64_t newest_camera_ = INT64_MIN;
  int64_t newest_odometry_ = INT64_MIN;
  int64_t consumed_until_ = INT64_MIN;  // end of the last cycle handed out
  Step ahead_;                          // a jump forward awaiting confirmation
  Step behind_;                         // a step back awaiting confirmation
  std::vector<SyncedCycle> restarted_;  // cycles handed out by a step back, for the next take_ready()
  int agreeing_[3] = {0, 0, 0};         // per input: samples in a row behind its own outlying newest time
  SyncCounters counters_;
};

}  // namespace whiskeye::slamd
