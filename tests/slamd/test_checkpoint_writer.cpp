#include "whiskeye/slamd/checkpoint_store.h"
#include "whiskeye/slamd/checkpoint_writer.h"
#include "scratch.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <whiskeye/driver_status_t.hpp>

#include <atomic>
#include <chrono>
#include <filesystem>
#include <future>
#include <mutex>
#include <stdexcept>
#include <vector>

namespace whiskeye::slamd {
namespace {

namespace fs = std::filesystem;
using ::testing::ElementsAre;
using ::testing::HasSubstr;
using namespace std::chrono_literals;

// A disk that records what it is given and, while `hold` is set, blocks inside the write until
// release() (a slow fsync), announcing that it is blocked.
class FakeDisk {
 public:
  explicit FakeDisk(bool hold = false) : hold_(hold) {}
  CheckpointWriter::WriteFn fn() {
    return [this](uint64_t sequence, std::vector<uint8_t>& payload) {
      if (sequence == fail_sequence_) throw std::runtime_error("/state/checkpoint: No space left on device");
      {
        std::lock_guard lock(mutex_);
        sequences_.push_back(sequence);
        sizes_.push_back(payload.size());
      }
      if (hold_) {
        hold_ = false;
        entered_.set_value();
        release_.get_future().wait();
      }
    };
  }
  void wait_until_blocked() { ASSERT_EQ(entered_.get_future().wait_for(10s), std::future_status::ready); }
  void release() { release_.set_value(); }
  void fail_on(uint64_t sequence) { fail_sequence_ = sequence; }
  std::vector<uint64_t> sequences() {
    std::lock_guard lock(mutex_);
    return sequences_;
  }
  std::vector<size_t> sizes() {
    std::lock_guard lock(mutex_);
    return sizes_;
  }

 private:
  bool hold_;
  uint64_t fail_sequence_ = UINT64_MAX;
  std::promise<void> entered_, release_;
  std::mutex mutex_;
  std::vector<uint64_t> sequences_;
  std::vector<size_t> sizes_;
};

std::vector<uint8_t> bytes(size_t n) { return std::vector<uint8_t>(n, 0x5a); }

TEST(CheckpointWriter, SubmitReturnsWhileTheDiskIsBusyAndTheNewestWaitingSnapshotWins) {
  FakeDisk disk(/*hold=*/true);
  CheckpointWriter writer(disk.fn(), nullptr);
  // The loop's thread must never wait for the disk: every submit returns although the disk holds
  // snapshot 1 until release() below (a submit that wrote itself would still be waiting).
  auto first = std::async(std::launch::async, [&] { writer.submit(1, bytes(10)); });
  disk.wait_until_blocked();  // snapshot 1 is stuck in a slow write
  auto later = std::async(std::launch::async, [&] {
    writer.submit(2, bytes(20));
    writer.submit(3, bytes(30));
  });
  const bool first_returned = first.wait_for(10s) == std::future_status::ready;
  const bool later_returned = later.wait_for(10s) == std::future_status::ready;
  const int64_t written_while_busy = writer.counters().written;
  disk.release();
  EXPECT_TRUE(first_returned);
  EXPECT_TRUE(later_returned);
  EXPECT_EQ(written_while_busy, 0);
  writer.finish();
  EXPECT_THAT(disk.sequences(), ElementsAre(1u, 3u));  // 2 was replaced by 3 while 1 was written
  EXPECT_THAT(disk.sizes(), ElementsAre(10u, 30u));
  const auto c = writer.counters();
  EXPECT_EQ(c.written, 2);
  EXPECT_EQ(c.superseded, 1);
  EXPECT_EQ(c.errors, 0);
}

TEST(CheckpointWriter, AFailedWriteIsLoggedAndCountedAndTheNextOneIsStillWritten) {
  FakeDisk disk;
  disk.fail_on(2);
  std::vector<std::string> log;
  std::mutex log_mutex;
  CheckpointWriter writer(disk.fn(), [&](const std::string& line) {
    std::lock_guard lock(log_mutex);
    log.push_back(line);
  });
  for (uint64_t s = 1; s <= 3; ++s) {
    writer.submit(s, bytes(8));
    // One at a time: wait until the writer has taken it (written or failed).
    for (int i = 0; i < 10000; ++i) {
      const auto c = writer.counters();
      if (c.written + c.errors == static_cast<int64_t>(s)) break;
      std::this_thread::sleep_for(1ms);
    }
  }
  writer.finish();
  EXPECT_THAT(disk.sequences(), ElementsAre(1u, 3u));
  const auto c = writer.counters();
  EXPECT_EQ(c.written, 2);
  EXPECT_EQ(c.errors, 1);
  EXPECT_FALSE(c.failing);
  ASSERT_EQ(log.size(), 2u);
  EXPECT_THAT(log[0], HasSubstr("checkpoint failed"));
  EXPECT_THAT(log[0], HasSubstr("No space left on device"));
  EXPECT_EQ(log[1], "checkpoints are written again, after 1 failed");
}

// With a full or read-only disk every checkpoint failed, logged every cycle, while SLAM_STATUS said
// OK: the loss showed only at exit. Now: DEGRADED with the reason, the log rate-limited, and OK again
// by itself once a checkpoint is written.
TEST(CheckpointWriter, AFailingDiskIsReportedDegradedWithTheReasonThrottledAndRecoversByItself) {
  std::atomic<bool> full{true};
  std::atomic<int64_t> now{0};
  std::vector<std::string> log;
  std::mutex log_mutex;
  CheckpointWriter writer(
      [&](uint64_t, std::vector<uint8_t>&) {
        if (full) throw std::runtime_error("/var/lib/slamd/.checkpoint-7.tmp: write failed: No space left on device");
      },
      [&](const std::string& line) {
        std::lock_guard lock(log_mutex);
        log.push_back(line);
      },
      [&] { return now.load(); });
  const auto submit_and_wait = [&](uint64_t s) {
    const auto before = writer.counters();
    writer.submit(s, bytes(8));
    for (int i = 0; i < 10000; ++i) {
      const auto c = writer.counters();
      if (c.written + c.errors > before.written + before.errors) return;
      std::this_thread::sleep_for(1ms);
    }
  };
  for (uint64_t s = 1; s <= 100; ++s, now += 100'000) submit_and_wait(s);  // 100 cycles in 10 s
  auto c = writer.counters();
  EXPECT_EQ(c.errors, 100);
  EXPECT_TRUE(c.failing);
  slam_status_t st{};
  st.state = driver_status_t::STATE_OK;
  report_checkpoints(st, c);
  EXPECT_EQ(st.state, driver_status_t::STATE_DEGRADED);
  EXPECT_THAT(st.message, HasSubstr("checkpoints failing, the map is not being saved: "));
  EXPECT_THAT(st.message, HasSubstr("No space left on device"));
  EXPECT_EQ(st.checkpoint_errors, 100);
  {
    std::lock_guard lock(log_mutex);
    ASSERT_EQ(log.size(), 1u) << "the first failure; the next line comes 10 s later";
  }
  submit_and_wait(101);
  {
    std::lock_guard lock(log_mutex);
    ASSERT_EQ(log.size(), 2u);
    EXPECT_THAT(log[1], HasSubstr("; 99 more like it suppressed in the last 10 s"));
  }
  full = false;  // space returns
  submit_and_wait(102);
  c = writer.counters();
  EXPECT_FALSE(c.failing);
  EXPECT_EQ(c.written, 1);
  slam_status_t ok{};
  ok.state = driver_status_t::STATE_OK;
  report_checkpoints(ok, c);
  EXPECT_EQ(ok.state, driver_status_t::STATE_OK);
  EXPECT_EQ(ok.message, "");
  writer.finish();
  std::lock_guard lock(log_mutex);
  ASSERT_EQ(log.size(), 3u);
  EXPECT_EQ(log[2], "checkpoints are written again, after 101 failed");
}

TEST(CheckpointWriter, FinishWritesWhatIsWaitingAndLaterSubmitsAreWrittenAtOnce) {
  FakeDisk disk(/*hold=*/true);
  CheckpointWriter writer(disk.fn(), nullptr);
  writer.submit(1, bytes(4));
  disk.wait_until_blocked();
  writer.submit(2, bytes(4));  // waiting behind 1
  disk.release();
  writer.finish();
  EXPECT_THAT(disk.sequences(), ElementsAre(1u, 2u));
  writer.submit(3, bytes(4));  // after finish: written before submit returns
  EXPECT_THAT(disk.sequences(), ElementsAre(1u, 2u, 3u));
  writer.finish();  // idempotent
  EXPECT_EQ(writer.counters().written, 3);
}

// slamd's exit status says whether its final state is on disk. An earlier snapshot that fails while
// the final one waits (the disk full until space was freed just before SIGTERM) does not make the
// final one lost: slamd once compared the error count before and after and exited 1, saying so.
TEST(CheckpointWriter, FinishSaysWhetherTheNewestSnapshotIsOnDiskNotWhetherAnEarlierOneFailed) {
  {
    std::promise<void> entered, release;
    CheckpointWriter writer(
        [&](uint64_t sequence, std::vector<uint8_t>&) {
          if (sequence != 1) return;
          entered.set_value();
          release.get_future().wait();  // a slow write of 1 ...
          throw std::runtime_error("/state/checkpoint: No space left on device");  // ... that fails
        },
        nullptr);
    writer.submit(1, bytes(4));
    ASSERT_EQ(entered.get_future().wait_for(10s), std::future_status::ready);
    writer.submit(2, bytes(4));  // the final state waits behind it
    release.set_value();         // 1 fails, then 2 is written
    EXPECT_TRUE(writer.finish());
    EXPECT_EQ(writer.counters().errors, 1);
    EXPECT_EQ(writer.counters().written, 1);
    EXPECT_TRUE(writer.finish()) << "idempotent";
  }
  {
    FakeDisk disk;
    disk.fail_on(2);
    CheckpointWriter writer(disk.fn(), nullptr);
    writer.submit(1, bytes(4));
    writer.submit(2, bytes(4));  // the final state fails
    EXPECT_FALSE(writer.finish());
  }
  CheckpointWriter idle([](uint64_t, std::vector<uint8_t>&) {}, nullptr);
  EXPECT_TRUE(idle.finish()) << "nothing submitted: nothing lost";
}

TEST(CheckpointWriter, WithTheRealStoreTheNewestSubmittedStateIsTheOneThatLoads) {
  const fs::path dir = whiskeye::testing::scratch_dir("cp_writer_store");
  CheckpointStore store(dir.string(), 3);
  {
    CheckpointWriter writer([&](uint64_t s, std::vector<uint8_t>& p) { store.write(s, p); }, nullptr);
    for (uint64_t s = 1; s <= 20; ++s) writer.submit(s, std::vector<uint8_t>(1000, static_cast<uint8_t>(s)));
  }  // the destructor finishes the writes
  std::vector<std::string> problems;
  const auto cp = store.load_newest(&problems);
  ASSERT_TRUE(cp.has_value());
  EXPECT_TRUE(problems.empty());
  EXPECT_EQ(cp->sequence, 20u);
  EXPECT_EQ(cp->payload, std::vector<uint8_t>(1000, 20));
  EXPECT_LE(store.list().size(), 3u);
}

}  // namespace
}  // namespace whiskeye::slamd
