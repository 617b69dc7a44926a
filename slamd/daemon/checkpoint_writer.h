// Checkpoints written on a thread of their own, so that slamd's LCM loop never waits for the disk.
//
// A checkpoint of a 10,000-template map is about 30 MB; written and fsync'ed after every whisk cycle
// on the loop's thread it held the loop for tens of milliseconds here and can hold it for a second on
// a robot's flash, while camera, odometry and whisker messages pile up in the socket buffer. The loop
// now only serialises the state (a consistent snapshot) and hands it over. At most one snapshot
// waits: a newer one replaces it, since only the newest state matters; each one replaced is counted
// (`superseded`), which says the disk cannot keep up with --checkpoint-every.
#pragma once

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
  };

  CheckpointWriter(WriteFn write, LogFn log);
  ~CheckpointWriter();  // finish()
  CheckpointWriter(const CheckpointWriter&) = delete;
  CheckpointWriter& operator=(const CheckpointWriter&) = delete;

  // Queues a snapshot and returns without touching the disk; replaces one still waiting.
  void submit(uint64_t sequence, std::vector<uint8_t> payload);
  // Writes the snapshot still waiting (if any), then stops the thread. Idempotent; a submit() from
  // then on is written on the caller's thread.
  void finish();

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
  std::mutex write_mutex_;  // held while writing
  mutable std::mutex mutex_;  // guards what follows
  std::condition_variable wake_;
  std::optional<Snapshot> pending_;
  bool stopping_ = false;
  Counters counters_;
  std::thread thread_;  // last: starts once everything above is built
};

}  // namespace whiskeye::slamd
