// What whiskeye-calibrate heard on the whisker bus, as plain data: every frame goes through the
// protocol's decoder and sample assembler (whiskeye/whisker_protocol), and each board's complete
// samples are kept per channel (board * 4 + k: the boards' own numbering, before whiskerd's wiring).
// Pure: frames in, with their times; the log reader and the live socket live in the tool's edge.
#pragma once

#include <array>
#include <cstdint>
#include <span>
#include <vector>

#include "whiskeye/whisker_protocol/whisker_protocol.h"

namespace whiskeye::calibrate {

inline constexpr int kChannels = wp::kNumWhiskers;

struct ChannelSample {
  int64_t utime = 0;
  int16_t x = 0, y = 0, theta = 0;  // counts
  bool fault = false;               // the whisker's or its board's fault bit
};

struct BoardCounts {
  int64_t samples = 0;     // complete samples
  int64_t heartbeats = 0;
  int64_t gaps = 0;        // samples lost between received sequence numbers
  int64_t fault_samples = 0;
  int64_t first_sample_utime = -1, last_sample_utime = -1;
  int64_t first_heartbeat_utime = -1, last_heartbeat_utime = -1;
  uint8_t nmt_state = 0;   // of the last heartbeat
};

class Recording {
 public:
  Recording(wp::BusMode mode, const wp::ProtocolIds& ids);

  void add_frame(int64_t utime, uint32_t id, bool fd, std::span<const uint8_t> data);
  void add_error_frame(int64_t utime);

  const std::vector<ChannelSample>& channel(int ch) const { return channels_[static_cast<std::size_t>(ch)]; }
  const BoardCounts& board(int b) const { return boards_[static_cast<std::size_t>(b)]; }
  wp::BusMode mode() const { return mode_; }
  int64_t frames() const { return frames_; }
  int64_t rejected() const { return rejected_; }
  int64_t error_frames() const { return error_frames_; }
  // Bus time of every frame received, worst-case stuffing at the nominal bit rates, microseconds.
  double busy_us() const { return busy_us_; }
  // First and last frame time in the order added (-1 before any).
  int64_t first_utime() const { return first_utime_; }
  int64_t last_utime() const { return last_utime_; }
  // The bus time the frames span, microseconds: the steps between frames in the order added, in
  // either direction, a step longer than kMaxPauseUs counting for nothing. A log in reverse spans
  // what it does forwards, two sessions one after the other their sum, and a frame with a wild time
  // (30 years late) nothing more, where "last minus first" made every rate 0 Hz.
  int64_t span_us() const { return span_us_; }
  // Longer than any pause of a bus whose boards stream (10 Hz at the least, heartbeats between): such
  // a step is no time spent listening to the boards (between two sessions, a wild time). A whole bus
  // silent for longer shows as sequence gaps, not as a lower rate.
  static constexpr int64_t kMaxPauseUs = 1'000'000;

 private:
  void seen(int64_t utime);
  wp::BusMode mode_;
  wp::ProtocolIds ids_;
  wp::SampleAssembler assembler_;
  std::array<std::vector<ChannelSample>, kChannels> channels_;
  std::array<BoardCounts, wp::kNumBoards> boards_{};
  int64_t frames_ = 0, rejected_ = 0, error_frames_ = 0;
  double busy_us_ = 0;
  int64_t first_utime_ = -1, last_utime_ = -1;
  int64_t span_us_ = 0;
};

}  // namespace whiskeye::calibrate
