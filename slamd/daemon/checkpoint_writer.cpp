#include "checkpoint_writer.h"

#include <exception>
#include <utility>

namespace whiskeye::slamd {

CheckpointWriter::CheckpointWriter(WriteFn write, LogFn log)
    : write_(std::move(write)), log_(std::move(log)), thread_([this] { run(); }) {}

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

void CheckpointWriter::finish() {
  {
    std::lock_guard lock(mutex_);
    if (stopping_) return;
    stopping_ = true;
    wake_.notify_one();
  }
  thread_.join();
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
  try {
    write_(s.sequence, s.payload);
    ok = true;
  } catch (const std::exception& e) {
    if (log_) log_(std::string("checkpoint failed: ") + e.what());
  }
  std::lock_guard lock(mutex_);
  ++(ok ? counters_.written : counters_.errors);
}

}  // namespace whiskeye::slamd
