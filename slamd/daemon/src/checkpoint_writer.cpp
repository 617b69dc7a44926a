#include "whiskeye/slamd/checkpoint_writer.h"

#include "whiskeye/common/clock.h"

#include <whiskeye/driver_status_t.hpp>

#include <exception>
#include <utility>

namespace whiskeye::slamd {

CheckpointWriter::CheckpointWriter(WriteFn write, LogFn log, std::function<int64_t()> clock)
    : write_(std::move(write)),
      log_(std::move(log)),
      clock_(clock ? std::move(clock) : std::function<int64_t()>([] { return monotonic_us(); })),
      thread_([this] { run(); }) {}

CheckpointWriter::~CheckpointWriter() { finish(); }

void CheckpointWriter::submit(uint64_t sequence, std::vector<uint8_t> payload) {
  Snapshot s{sequence, std::move(payload)};
  {
    std::lock_guard lock(mutex_);
    if (!stopping_) {
      if (pending_) ++counters_.superseded;
      pending_ = std::move(s);
      wake_.notify_one();
      return;
    }
  }
  write_one(s);  // after finish(): no thread left to hand it to
}

bool CheckpointWriter::finish() {
  {
    std::lock_guard lock(mutex_);
    if (!stopping_) {
      stopping_ = true;
      wake_.notify_one();
    }
  }
  if (thread_.joinable()) thread_.join();
  std::lock_guard lock(mutex_);
  return !counters_.failing;  // the newest write is the last one made: written unless it failed
}

CheckpointWriter::Counters CheckpointWriter::counters() const {
  std::lock_guard lock(mutex_);
  return counters_;
}

void CheckpointWriter::run() {
  std::unique_lock lock(mutex_);
  for (;;) {
    wake_.wait(lock, [this] { return pending_.has_value() || stopping_; });
    if (!pending_) return;  // stopping, nothing left to write
    Snapshot s = std::move(*pending_);
    pending_.reset();
    lock.unlock();
    write_one(s);
    lock.lock();
  }
}

void CheckpointWriter::write_one(Snapshot& s) {
  std::lock_guard serial(write_mutex_);  // the thread's last write and a late caller's never overlap
  bool ok = false;
  std::string failure;
  try {
    write_(s.sequence, s.payload);
    ok = true;
  } catch (const std::exception& e) {
    failure = e.what();
  }
  if (!ok) {
    ++failures_in_a_row_;
    const auto line = throttle_.admit("checkpoint", "checkpoint failed: " + failure, clock_());
    if (line && log_) log_(*line);
  } else if (failures_in_a_row_ > 0) {
    if (log_) log_("checkpoints are written again, after " + std::to_string(failures_in_a_row_) + " failed");
    failures_in_a_row_ = 0;
  }
  std::lock_guard lock(mutex_);
  ++(ok ? counters_.written : counters_.errors);
  counters_.failing = !ok;
  counters_.failure = failure;
}

void report_checkpoints(slam_status_t& status, const CheckpointWriter::Counters& counters) {
  status.checkpoints_written = counters.written;
  status.checkpoint_errors = counters.errors;
  status.checkpoints_superseded = counters.superseded;
  if (!counters.failing) return;
  status.state = driver_status_t::STATE_DEGRADED;
  status.message += std::string(status.message.empty() ? "" : "; ") +
                    "checkpoints failing, the map is not being saved: " + counters.failure;
}

}  // namespace whiskeye::slamd
