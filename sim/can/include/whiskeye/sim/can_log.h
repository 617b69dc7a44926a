// The simulated whisker traffic as CAN frames: what the six whisker boards would send on the bus
// (docs/can-protocol.md) for the simulator's whisker samples, written in the text format of
// `candump -l` so that can-utils' `canplayer` can replay it into a (v)can interface in front of the
// real whiskerd. Values go through the inverse of whiskerd's calibration (wp::uncalibrate) and the
// protocol's own encoders, so whiskerd calibrates them back to the simulated angles and deflections
// within one count. Not part of the pure simulator library (it knows the drivers' protocol); no
// clocks: frames carry the samples' utime.
#pragma once

#include "whiskeye/can/candump.h"
#include "whiskeye/whisker_protocol/whisker_protocol.h"
#include "whiskeye/sim/simulator.h"

#include <whiskeye/rcp/types.h>

#include <array>
#include <cstdint>
#include <ostream>
#include <string>
#include <string_view>
#include <vector>

namespace whiskeye::sim {

// The frames and the `candump -l` text format (whiskeye/can/candump.h).
using CanFrame = can::LoggedFrame;
using can::format_candump_line;
using can::kCanFdBrs;
using can::parse_candump_line;

struct BoardTrafficParams {
  wp::BusMode mode = wp::BusMode::kFd;
  double rate_hz = kControlRateHz;  // board sample rate; FD 500 Hz, classic 100 Hz (docs/can-protocol.md)
  double heartbeat_hz = wp::kHeartbeatHz;  // per board
  wp::ProtocolIds ids;
  std::array<wp::WhiskerCalibration, wp::kNumWhiskers> calibration{};
  // Whisker w's sensor is on board channel channel[w] (whiskerd's `channel`; a permutation).
  std::array<int, wp::kNumWhiskers> channel = identity_channels();
  static constexpr std::array<int, wp::kNumWhiskers> identity_channels() {
    std::array<int, wp::kNumWhiskers> a{};
    for (int w = 0; w < wp::kNumWhiskers; ++w) a[static_cast<std::size_t>(w)] = w;
    return a;
  }
  uint16_t first_seq = 0;        // seq of the first sample (FD: 16 bit, classic: its low 8 bits)
  uint8_t nmt_state = 0x05;      // heartbeat: operational
};

// Turns simulator whisker samples into the boards' frames. The boards sample at rate_hz: a sample
// is sent when its utime reaches the next board period (counted from the first sample), so with the
// simulator's 500 Hz every sample goes out in FD mode and every fifth in classic mode at 100 Hz.
// Heartbeats follow the same rule at heartbeat_hz, after the sample frames of their instant.
// A whisker marked faulty carries the whisker fault bit. A board whose whiskers are stale is offline
// (its cable unplugged): it sends neither sample frames nor heartbeats, while it keeps sampling, so
// its sequence counter jumps by the samples it missed when it is back (whiskerd counts a gap).
class BoardTraffic {
 public:
  explicit BoardTraffic(const BoardTrafficParams& params);
  // Appends this sample's frames (possibly none) to `out`.
  void add(const rcp::WhiskerSample& sample, const WhiskerHealth& health, std::vector<CanFrame>& out);
  int64_t samples_sent() const { return samples_sent_; }

 private:
  BoardTrafficParams params_;
  int64_t sample_period_us_;
  int64_t heartbeat_period_us_;
  bool started_ = false;
  int64_t next_sample_utime_ = 0;
  int64_t next_heartbeat_utime_ = 0;
  int64_t samples_sent_ = 0;
};

// BoardTraffic written to a stream as `candump -l` lines on one interface name.
class CandumpWriter {
 public:
  CandumpWriter(std::ostream& out, const BoardTrafficParams& params, std::string interface);
  void whisker_sample(const rcp::WhiskerSample& sample, const WhiskerHealth& health);
  int64_t frames_written() const { return frames_written_; }
  int64_t samples_sent() const { return traffic_.samples_sent(); }

 private:
  std::ostream& out_;
  BoardTraffic traffic_;
  std::string interface_;
  std::vector<CanFrame> frames_;
  int64_t frames_written_ = 0;
};

}  // namespace whiskeye::sim
