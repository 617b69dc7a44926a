// The simulated whisker traffic as CAN frames: what the six whisker boards would send on the bus
// (docs/can-protocol.md) for the simulator's whisker samples, written in the text format of
// `candump -l` so that can-utils' `canplayer` can replay it into a (v)can interface in front of the
// real whiskerd. Values go through the inverse of whiskerd's calibration (wp::uncalibrate) and the
// protocol's own encoders, so whiskerd calibrates them back to the simulated angles and deflections
// within one count. Not part of the pure simulator library (it knows the drivers' protocol); no
// clocks: frames carry the samples' utime.
#pragma once

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

// One CAN frame of a log: time, 11-bit id, FD or classic, FD flags (bit 0 BRS, bit 1 ESI) and data.
struct CanFrame {
  int64_t utime = 0;
  uint32_t id = 0;
  bool fd = false;
  uint8_t fd_flags = 0;
  std::vector<uint8_t> data;
};

// FD frames go out with bit-rate switching (the bus runs 1/5 Mbit/s, docs/can-protocol.md).
inline constexpr uint8_t kCanFdBrs = 0x01;

// One line of `candump -l`, without the newline: "(1700000000.002000) can0 181##1<hex>" for an FD
// frame, "(1700000000.002000) can0 701#0500" for a classic one (ids as 3 hex digits, uppercase).
std::string format_candump_line(const CanFrame& frame, std::string_view interface);
// Parses one such line (the `candump -l` subset above: standard ids, data frames). False on any
// other text.
bool parse_candump_line(std::string_view line, CanFrame& frame, std::string& interface);

struct BoardTrafficParams {
  wp::BusMode mode = wp::BusMode::kFd;
  double rate_hz = 500.0;        // board sample rate; FD 500 Hz, classic 100 Hz (docs/can-protocol.md)
  double heartbeat_hz = 10.0;    // per board
  wp::ProtocolIds ids;
  std::array<wp::WhiskerCalibration, wp::kNumWhiskers> calibration{};
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
