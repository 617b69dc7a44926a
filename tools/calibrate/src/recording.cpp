// What whiskeye-calibrate heard on the bus (see recording.h).
#include "whiskeye/calibrate/recording.h"

namespace whiskeye::calibrate {

Recording::Recording(wp::BusMode mode, const wp::ProtocolIds& ids) : mode_(mode), ids_(ids), assembler_(mode) {}

void Recording::seen(int64_t utime) {
  if (first_utime_ < 0) {
    first_utime_ = utime;
  } else {
    // Unsigned: the step between any two int64 times, never an overflow.
    const uint64_t a = static_cast<uint64_t>(utime), b = static_cast<uint64_t>(last_utime_);
    const uint64_t step = utime >= last_utime_ ? a - b : b - a;
    if (step <= static_cast<uint64_t>(kMaxPauseUs)) span_us_ += static_cast<int64_t>(step);
  }
  last_utime_ = utime;
}

void Recording::add_error_frame(int64_t utime) {
  seen(utime);
  ++error_frames_;
}

void Recording::add_frame(int64_t utime, uint32_t id, bool fd, std::span<const uint8_t> data) {
  seen(utime);
  ++frames_;
  busy_us_ += wp::frame_time_us(fd ? wp::BusMode::kFd : wp::BusMode::kClassic, data.size(), wp::kArbitrationBps,
                                wp::kFdDataBps);
  const wp::Decoded d = wp::decode_frame(id, fd, data, mode_, ids_);
  int board = -1;
  bool complete = false;
  switch (d.kind) {
    case wp::FrameKind::kRejected: ++rejected_; return;
    case wp::FrameKind::kCommand: return;
    case wp::FrameKind::kHeartbeat: {
      BoardCounts& b = boards_[static_cast<std::size_t>(d.heartbeat.board)];
      ++b.heartbeats;
      if (b.first_heartbeat_utime < 0) b.first_heartbeat_utime = utime;
      b.last_heartbeat_utime = utime;
      b.nmt_state = d.heartbeat.state;
      if (d.heartbeat.state == wp::kNmtBootUp) assembler_.restart(d.heartbeat.board);
      return;
    }
    case wp::FrameKind::kSample:
      board = d.sample.board;
      complete = assembler_.add(d.sample);
      break;
    case wp::FrameKind::kFragment:
      board = d.fragment.board;
      complete = assembler_.add(d.fragment);
      break;
  }
  if (board < 0 || board >= wp::kNumBoards) return;  // the decoder never gives one; the compiler cannot know
  BoardCounts& b = boards_[static_cast<std::size_t>(board)];
  b.gaps = assembler_.gaps(board);
  if (!complete) return;
  const wp::BoardSample& s = assembler_.latest(board);
  ++b.samples;
  if (b.first_sample_utime < 0) b.first_sample_utime = utime;
  b.last_sample_utime = utime;
  bool any_fault = false;
  for (int k = 0; k < wp::kWhiskersPerBoard; ++k) {
    const wp::WhiskerRaw& raw = s.whiskers[static_cast<std::size_t>(k)];
    const bool fault = raw.fault || (s.status & wp::kBoardFault);
    any_fault = any_fault || fault;
    channels_[static_cast<std::size_t>(board * wp::kWhiskersPerBoard + k)].push_back({utime, raw.x, raw.y, raw.theta, fault});
  }
  if (any_fault) ++b.fault_samples;
}

}  // namespace whiskeye::calibrate
