// Checkpoints written on a thread of their own, so that slamd's LCM loop never waits for the disk.
//
// A checkpoint of a 10,000-template map is about 30 MB; written and fsync'ed after every whisk cycle
// on the loop's thread it held the loop for tens of milliseconds here and can hold it for a second on
// a robot's flash, while camera, odometry and whisker messages pile up in the socket buffer. The loop
// now only serialises the state (a consistent snapshot) and hands it over. At most one snapshot
// waits: a newer one replaces it, since only the newest state matters; each one replaced is counted
// (`superseded`), which says the disk cannot keep up with --checkpoint-every.
//
// A failing disk (full, read-only) is not silent: the first failure is logged, then at most one line
// per 10 s with the count held back (LogThrottle), the writer keeps trying with every new snapshot,
// and `failing` says so until one is written again (logged too), so that SLAM_STATUS can report it
// (report_checkpoints()).
#pragma once

#include "whiskeye/common/log_throttle.h"

#include <whiskeye/slam_status_t.hpp>

#include <condition_variable>
#include <cstdint>
#include <functional>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

namespace whiskeye::slamd {

class CheckpointWriter {
 public:
  // Called on the writer thread for every snapshot written (it may finish the payload first, e.g.
  // append its checksum); throws on failure (the message is logged and counted, the thread goes on).
  using WriteFn = std::function<void(uint64_t sequence, std::vector<uint8_t>& payload)>;
  using LogFn = std::function<void(const std::string&)>;

  struct Counters {
    int64_t written = 0;
    int64_t errors = 0;
    int64_t superseded = 0;  // snapshots replaced by a newer one before they were written
    bool failing = false;    // the latest write failed (none since succeeded)
    std::string failure;     // its reason, while failing
  };

  // `clock`: monotonic microseconds for the log's rate limit (default: the monotonic clock).
  CheckpointWriter(WriteFn write, LogFn log, std::function<int64_t()> clock = {});
  ~CheckpointWriter();  // finish()
  CheckpointWriter(const CheckpointWriter&) = delete;
  CheckpointWriter& operator=(const CheckpointWriter&) = delete;

  // Queues a snapshot and returns without touching the disk; replaces one still waiting.
  void submit(uint64_t sequence, std::vector<uint8_t> payload);
  // Writes the snapshot still waiting (if any), then stops the thread. Idempotent; a submit() from
  // then on is written on the caller's thread. Returns whether the newest snapshot submitted is on
  // disk (true when none was): an earlier write failing while this one waited does not make it lost.
  bool finish();

  Counters counters() const;

 private:
  struct Snapshot {
    uint64_t sequence = 0;
    std::vector<uint8_t> payload;
  };
  void run();
  void write_one(Snapshot& s);

  WriteFn write_;
  LogFn log_;
  std::function<int64_t()> clock_;
  LogThrottle throttle_;
  int64_t failures_in_a_row_ = 0;  // under write_mutex_
  std::mutex write_mutex_;  // held while writing
  mutable std::mutex mutex_;  // guards what follows
  std::condition_variable wake_;
  std::optional<Snapshot> pending_;
  bool stopping_ = false;
  Counters counters_;
  std::thread thread_;  // last: starts once everything above is built
};

// The writer's counters into SLAM_STATUS; while checkpoints fail, the state is DEGRADED and the
// message says why (the map is not being saved: a full or read-only disk showed only at exit).
void report_checkpoints(slam_status_t& status, const CheckpointWriter::Counters& counters);

}  // namespace whiskeye::slamd
