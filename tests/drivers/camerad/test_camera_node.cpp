// CameraNode's states driven with a scripted capture and a fake clock, on a MemoryBus: a failed open
// backs off, frames give OK, silence gives DEGRADED and then a reopen, a lost device is reopened and
// counted, a damaged frame is counted and never published.
#include <gtest/gtest.h>

#include <deque>
#include <memory>
#include <string>
#include <vector>

#include "whiskeye/camerad/camera_node.h"
#include "whiskeye/common/params.h"

namespace {

using namespace whiskeye;
using camerad::CameraNode;
using camerad::CaptureSession;
using v4l2::Capture;

constexpr int64_t kStartUs = 5'000'000;                 // monotonic time at construction
constexpr int64_t kEpochOffsetUs = 1'700'000'000'000'000;  // now_utime - monotonic

struct FakeTime {
  int64_t now_us = kStartUs;
};

// One scripted call of next(): its result, and how long it took.
struct Event {
  Capture::Result result = Capture::Result::kFrame;
  int64_t took_us = 100'000;
  uint32_t sequence = 0;
  v4l2::FrameCheck skip = v4l2::FrameCheck::kUsable;
  bool torn = false;  // a frame the driver writes again while it is read (v4l2loopback's ring)
};

class FakeSession final : public CaptureSession {
 public:
  FakeSession(FakeTime& time, std::deque<Event> script) : time_(time), script_(std::move(script)) {}
  Capture::Result next(v4l2::FrameView& frame, int timeout_ms) override {
    if (script_.empty()) {
      time_.now_us += int64_t{timeout_ms} * 1000;
      return Capture::Result::kTimeout;
    }
    const Event e = script_.front();
    script_.pop_front();
    time_.now_us += e.took_us;
    if (e.result == Capture::Result::kFrame) {
      frame.data = pixels_.data();
      frame.size = pixels_.size();
      frame.width = 2;
      frame.height = 2;
      frame.stride = 2;
      frame.pixelformat = v4l2::kGREY;
      frame.utime = time_.now_us + kEpochOffsetUs - 1000;  // captured 1 ms ago
      frame.sequence = e.sequence;
      lent_torn_ = e.torn;
    } else if (e.result == Capture::Result::kSkipped) {
      ++corrupt_;
      last_skip_ = e.skip;
    } else if (e.result == Capture::Result::kGone) {
      last_error_ = device_ + ": VIDIOC_DQBUF: No such device";
    }
    return e.result;
  }
  const std::string& device() const override { return device_; }
  uint32_t width() const override { return 2; }
  uint32_t height() const override { return 2; }
  uint32_t pixelformat() const override { return v4l2::kGREY; }
  double fps() const override { return 10.0; }
  std::size_t num_buffers() const override { return 4; }
  const std::string& last_error() const override { return last_error_; }
  int64_t corrupt_frames() const override { return corrupt_; }
  v4l2::FrameCheck last_skip() const override { return last_skip_; }
  int64_t requeue_failures() const override { return 0; }
  bool lent_frame_overwritten() override {
    if (!lent_torn_) return false;
    ++corrupt_;
    ++overwritten_;
    last_skip_ = v4l2::FrameCheck::kOverwritten;
    return true;
  }
  int64_t overwritten_frames() const override { return overwritten_; }

 private:
  FakeTime& time_;
  std::deque<Event> script_;
  std::vector<uint8_t> pixels_{10, 20, 30, 40};
  std::string device_ = "/dev/video0";
  std::string last_error_;
  int64_t corrupt_ = 0, overwritten_ = 0;
  bool lent_torn_ = false;
  v4l2::FrameCheck last_skip_ = v4l2::FrameCheck::kUsable;
};

Event frame(uint32_t sequence) {
  Event e;
  e.sequence = sequence;
  return e;
}
// The device vanishes (ENODEV) at once.
Event gone() {
  Event e;
  e.result = Capture::Result::kGone;
  e.took_us = 0;
  return e;
}
// A damaged buffer, 100 ms after the previous one.
Event damaged(v4l2::FrameCheck why) {
  Event e;
  e.result = Capture::Result::kSkipped;
  e.skip = why;
  return e;
}

// `n` frames, 100 ms apart (10 fps), numbered from `first`.
std::deque<Event> frames(int n, uint32_t first = 0) {
  std::deque<Event> s;
  for (int i = 0; i < n; ++i) s.push_back(frame(first + static_cast<uint32_t>(i)));
  return s;
}

class CameraNodeTest : public ::testing::Test {
 protected:
  CameraNodeTest() {
    subscribe<image_t>(bus_, params_.channel, [this](const image_t& m) { images_.push_back(m); }, errors_);
    subscribe<driver_status_t>(bus_, params_.channel_status,
                               [this](const driver_status_t& m) { statuses_.push_back(m); }, errors_);
  }

  // Each open takes the next script, or fails as a missing device when none is left.
  void add_session(std::deque<Event> script) { scripts_.push_back(std::move(script)); }

  CameraNode& node() {
    if (!node_) {
      camerad::Clock clock{[this] { return time_.now_us; }, [this] { return time_.now_us + kEpochOffsetUs; },
                           [this](int64_t us) { time_.now_us += us; }};
      auto open = [this](const v4l2::CaptureConfig& config) -> std::unique_ptr<CaptureSession> {
        open_attempts_us_.push_back(time_.now_us - kStartUs);
        time_.now_us += open_takes_us_;
        if (scripts_.empty()) throw v4l2::CaptureError(config.device + ": cannot open: No such file or directory", true);
        auto s = std::make_unique<FakeSession>(time_, std::move(scripts_.front()));
        scripts_.pop_front();
        return s;
      };
      node_ = std::make_unique<CameraNode>(bus_, params_, open, clock,
                                           [this](LogLevel level, const std::string& line) {
                                             log_.push_back(line);
                                             levels_.push_back(level);
                                           });
      node_->set_ready_hook([this] { ++ready_calls_; });
    }
    return *node_;
  }

  // Steps until `until_us` after construction.
  void run_until(int64_t until_us) {
    while (time_.now_us - kStartUs < until_us) node().step();
  }

  int64_t counter(const driver_status_t& st, const std::string& name) const {
    for (std::size_t i = 0; i < st.counter_names.size(); ++i) {
      if (st.counter_names[i] == name) return st.counter_values[i];
    }
    ADD_FAILURE() << "no counter " << name;
    return -1;
  }

  int log_lines_containing(const std::string& text) const {
    int n = 0;
    for (const std::string& l : log_) n += l.find(text) != std::string::npos;
    return n;
  }
  // The priority of the first line containing `text` (common/log.h), or -1 when there is none.
  int level_of(const std::string& text) const {
    for (std::size_t i = 0; i < log_.size(); ++i) {
      if (log_[i].find(text) != std::string::npos) return static_cast<int>(levels_[i]);
    }
    return -1;
  }

  camerad::Params params_;
  MemoryBus bus_;
  DecodeErrors errors_;
  FakeTime time_;
  std::deque<std::deque<Event>> scripts_;
  std::vector<int64_t> open_attempts_us_;
  int64_t open_takes_us_ = 0;  // how long each open takes
  std::unique_ptr<CameraNode> node_;
  std::vector<image_t> images_;
  std::vector<driver_status_t> statuses_;
  std::vector<std::string> log_;
  std::vector<LogLevel> levels_;
  int ready_calls_ = 0;
};

TEST_F(CameraNodeTest, FailedOpenBacksOffDoublingAndReportsDegraded) {
  run_until(1'500'000);
  // 0.2 s, then 0.4 s, then 0.8 s between attempts (reopen_initial_s 0.2, doubling).
  EXPECT_EQ(open_attempts_us_, (std::vector<int64_t>{0, 200'000, 600'000, 1'400'000}));
  EXPECT_EQ(ready_calls_, 1) << "READY once, after the first attempt, camera or not";
  ASSERT_EQ(statuses_.size(), 1u);
  const driver_status_t& st = statuses_[0];
  EXPECT_EQ(st.driver, "camerad");
  EXPECT_EQ(st.state, driver_status_t::STATE_DEGRADED);
  EXPECT_EQ(st.message, "no camera: /dev/video0: cannot open: No such file or directory");
  EXPECT_EQ(counter(st, "open_failures"), 3);
  EXPECT_EQ(counter(st, "frames"), 0);
  EXPECT_EQ(log_lines_containing("; retrying"), 1) << "the same error is logged once";
  EXPECT_EQ(level_of("; retrying"), static_cast<int>(LogLevel::kWarning));
  EXPECT_TRUE(images_.empty());
}

TEST_F(CameraNodeTest, BackoffIsCappedAtReopenMax) {
  params_.reopen_max_s = 0.5;
  run_until(2'000'000);
  EXPECT_EQ(open_attempts_us_, (std::vector<int64_t>{0, 200'000, 600'000, 1'100'000, 1'600'000}));
}

TEST_F(CameraNodeTest, FramesArrivingArePublishedAndReportOk) {
  add_session(frames(12));
  run_until(1'000'000);
  ASSERT_EQ(ready_calls_, 1);
  ASSERT_GE(images_.size(), 9u);
  EXPECT_EQ(images_[0].width, 2);
  EXPECT_EQ(images_[0].pixelformat, static_cast<int32_t>(v4l2::kGREY));
  EXPECT_EQ(images_[0].data, (std::vector<uint8_t>{10, 20, 30, 40}));
  EXPECT_EQ(images_[3].seq, 3);
  ASSERT_EQ(statuses_.size(), 1u);
  const driver_status_t& st = statuses_[0];
  EXPECT_EQ(st.state, driver_status_t::STATE_OK) << st.message;
  EXPECT_EQ(st.message, "/dev/video0 2x2 GREY");
  EXPECT_EQ(counter(st, "frames"), static_cast<int64_t>(images_.size()));
  EXPECT_EQ(counter(st, "sequence_gaps"), 0);
  EXPECT_EQ(counter(st, "reopens"), 0);
  EXPECT_EQ(st.stat_names[0], "fps");
  EXPECT_DOUBLE_EQ(st.stat_values[0], static_cast<double>(images_.size()));
  EXPECT_DOUBLE_EQ(st.stat_values[1], 1000.0) << "latency: captured 1 ms before it was read";
  EXPECT_EQ(log_lines_containing("camerad: streaming /dev/video0 2x2 GREY at 10 fps, 4 buffers"), 1);
  EXPECT_EQ(level_of("camerad: streaming"), static_cast<int>(LogLevel::kInfo)) << "opening is progress, not a warning";
}

TEST_F(CameraNodeTest, SkippedSequenceNumbersAreCountedAsGaps) {
  std::deque<Event> s = frames(3);  // 0, 1, 2
  for (const Event& e : frames(3, 6)) s.push_back(e);  // 6, 7, 8: 3, 4, 5 lost
  add_session(std::move(s));
  run_until(1'000'000);
  ASSERT_EQ(statuses_.size(), 1u);
  EXPECT_EQ(counter(statuses_[0], "sequence_gaps"), 3);
}

TEST_F(CameraNodeTest, SilenceIsDegradedThenTheDeviceIsReopened) {
  add_session(frames(5));  // 0.5 s of frames, then nothing
  add_session(frames(20));
  run_until(1'000'000);
  ASSERT_EQ(statuses_.size(), 1u);
  EXPECT_EQ(statuses_[0].state, driver_status_t::STATE_OK) << "0.5 s of silence is within the 1 s allowed";
  run_until(2'000'000);
  ASSERT_EQ(statuses_.size(), 2u);
  EXPECT_EQ(statuses_[1].state, driver_status_t::STATE_DEGRADED);
  EXPECT_EQ(statuses_[1].message, "/dev/video0 2x2 GREY: no frame for 1.6 s");
  EXPECT_EQ(counter(statuses_[1], "device_lost"), 0) << "frame_timeout_s (2 s) not reached yet";
  run_until(4'000'000);
  // Lost once the last frame (0.5 s) is more than 2 s old; reopened after the initial backoff (the
  // first session's frames reset it).
  ASSERT_EQ(open_attempts_us_.size(), 2u);
  EXPECT_EQ(open_attempts_us_[1], 2'900'000) << "lost at 2.7 s (the first timeout past 2.5 s), + 0.2 s";
  EXPECT_EQ(log_lines_containing("/dev/video0: no frames; closing and reopening"), 1);
  EXPECT_EQ(level_of("no frames; closing and reopening"), static_cast<int>(LogLevel::kWarning));
  const driver_status_t& st = statuses_.back();
  EXPECT_EQ(counter(st, "device_lost"), 1);
  EXPECT_EQ(counter(st, "reopens"), 1);
  EXPECT_EQ(st.state, driver_status_t::STATE_OK) << st.message;
}

// Opening a camera can take seconds (STREAMON on some UVC cameras); the time without frames starts
// when it streams. It once started before the open, so a camera slower to start than
// frame_timeout_s (2 s) was declared lost before its first frame, again at every reopen.
TEST_F(CameraNodeTest, TheTimeAnOpenTakesIsNotTimeWithoutFrames) {
  open_takes_us_ = 2'100'000;
  Event waiting;  // the first frame is 0.2 s in coming
  waiting.result = Capture::Result::kTimeout;
  waiting.took_us = 200'000;
  std::deque<Event> s = frames(10);
  s.push_front(waiting);
  add_session(std::move(s));
  run_until(3'500'000);
  EXPECT_EQ(open_attempts_us_.size(), 1u);
  EXPECT_EQ(log_lines_containing("closing and reopening"), 0);
  EXPECT_EQ(images_.size(), 10u);
  ASSERT_FALSE(statuses_.empty());
  EXPECT_EQ(counter(statuses_.back(), "device_lost"), 0);
}

TEST_F(CameraNodeTest, LostDeviceIsClosedReopenedAndCounted) {
  std::deque<Event> s = frames(3);
  s.push_back(gone());
  add_session(std::move(s));
  add_session(frames(20, 100));
  run_until(1'000'000);
  ASSERT_EQ(open_attempts_us_.size(), 2u);
  EXPECT_EQ(open_attempts_us_[1], 300'000 + 200'000) << "gone at 0.3 s, reopened after the initial 0.2 s";
  EXPECT_EQ(log_lines_containing("/dev/video0: VIDIOC_DQBUF: No such device; closing and reopening"), 1);
  ASSERT_EQ(statuses_.size(), 1u);
  EXPECT_EQ(counter(statuses_[0], "device_lost"), 1);
  EXPECT_EQ(counter(statuses_[0], "reopens"), 1);
  EXPECT_EQ(counter(statuses_[0], "open_failures"), 0);
  EXPECT_EQ(statuses_[0].state, driver_status_t::STATE_OK) << statuses_[0].message;
}

TEST_F(CameraNodeTest, DamagedFrameIsCountedLoggedOnceAndNotPublished) {
  std::deque<Event> s = frames(1);
  s.push_back(damaged(v4l2::FrameCheck::kShortPayload));
  s.push_back(damaged(v4l2::FrameCheck::kShortPayload));
  s.push_back(frame(3));
  s.push_back(gone());
  add_session(std::move(s));
  add_session(frames(20, 10));
  run_until(450'000);
  EXPECT_EQ(images_.size(), 2u) << "damaged buffers are not published";
  EXPECT_EQ(log_lines_containing("skipping a frame"), 1) << "one line per reason and session";
  run_until(1'000'000);
  ASSERT_EQ(statuses_.size(), 1u);
  EXPECT_EQ(counter(statuses_[0], "corrupt_frames"), 2) << "a closed session's count is kept";
  EXPECT_EQ(counter(statuses_[0], "device_lost"), 1);
}

TEST_F(CameraNodeTest, AFrameOverwrittenWhileItWasReadIsCountedApartAndNotPublished) {
  std::deque<Event> s = frames(4);
  s[1].torn = true;
  s[2].torn = true;
  s.push_back(gone());
  add_session(std::move(s));
  add_session(frames(20, 10));
  run_until(1'000'000);
  ASSERT_GE(images_.size(), 2u);
  EXPECT_EQ(images_[0].seq, 0);
  EXPECT_EQ(images_[1].seq, 3) << "torn frames 1 and 2 are not published";
  EXPECT_EQ(log_lines_containing("skipping a frame overwritten by the driver while it was read (torn)"), 1);
  ASSERT_EQ(statuses_.size(), 1u);
  EXPECT_EQ(counter(statuses_[0], "corrupt_frames"), 2);
  EXPECT_EQ(counter(statuses_[0], "overwritten_frames"), 2) << "a closed session's count is kept";
}

TEST_F(CameraNodeTest, OnlyDamagedFramesIsDegradedAndReopened) {
  std::deque<Event> s;
  for (int i = 0; i < 30; ++i) s.push_back(damaged(v4l2::FrameCheck::kErrorFlag));
  add_session(std::move(s));
  run_until(1'000'000);
  ASSERT_EQ(statuses_.size(), 1u);
  EXPECT_EQ(statuses_[0].state, driver_status_t::STATE_DEGRADED);
  EXPECT_EQ(statuses_[0].message, "/dev/video0 2x2 GREY: open for 1.0 s, only damaged frames (10)");
  run_until(2'400'000);
  // No frame since the open for more than frame_timeout_s (2 s): closed at 2.1 s, reopened 0.2 s later.
  EXPECT_EQ(open_attempts_us_, (std::vector<int64_t>{0, 2'300'000}));
}

}  // namespace

// A backoff whose cap is below its start would reopen at the cap from the first failure on: refused.
TEST(CameradParams, AReopenCapBelowTheFirstDelayIsRefusedNamingBoth) {
  camerad::Params p;
  try {
    camerad::load(ParamNode::from_string("camera:\n  reopen_initial_s: 2.0\n  reopen_max_s: 1.0\n"), p);
    FAIL() << "expected a ParamError";
  } catch (const ParamError& e) {
    EXPECT_NE(std::string(e.what()).find("camera.reopen_max_s must be >= camera.reopen_initial_s"), std::string::npos)
        << e.what();
  }
  EXPECT_NO_THROW(camerad::load(ParamNode::from_string("camera:\n  reopen_initial_s: 1.0\n  reopen_max_s: 1.0\n"), p));
}
