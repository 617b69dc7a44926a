// The WhiskEye whisker CAN protocol (docs/can-protocol.md, version 1): pure encode/decode functions
// over byte spans, a per-board sample assembler that counts sequence gaps, per-whisker calibration
// and a bus-load calculator. No sockets, no clocks: testable and fuzzable without a bus.
//
// 24 whiskers on 6 boards x 4. Board b (0..5) has CANopen node id b+1. Whisker index w = board*4 + k
// (k = 0..3 on the board), which is also the LCM index row*6+col because the boards are wired so
// (see docs/can-protocol.md).
#pragma once

#include <whiskeye/common/se2.h>
#include <whiskeye/common/whisker_array.h>

#include <array>
#include <cstddef>
#include <cstdint>
#include <span>
#include <string>

namespace whiskeye::wp {

inline constexpr int kProtocolVersion = 1;
// The array's boards and whiskers (common/whisker_array.h).
using whiskeye::kNumBoards;
using whiskeye::kNumWhiskers;
using whiskeye::kWhiskersPerBoard;

// Value ranges. Hall sensors: 12-bit signed ADC; |value| == kHallLimit means saturated, beyond is
// impossible and rejected. Protraction encoder: 4096 counts per revolution, signed around the rest
// position; the joint range is +-60 deg, so |counts| > kThetaLimit (+-90 deg) is rejected.
inline constexpr int16_t kHallLimit = 2047;
inline constexpr int16_t kThetaLimit = 1024;
inline constexpr double kThetaRadPerCount = kTwoPi / 4096.0;

// Every board's heartbeat rate (CANopen producer time 100 ms).
inline constexpr double kHeartbeatHz = 10.0;
// The bus's bit rates (docs/can-protocol.md): arbitration 1 Mbit/s, FD data phase 5 Mbit/s.
inline constexpr double kArbitrationBps = 1e6;
inline constexpr double kFdDataBps = 5e6;

// FD mode frame sizes (bytes); classic mode frames are always 8 bytes.
inline constexpr std::size_t kFdSampleBytes = 32;
inline constexpr std::size_t kFdCommandBytes = 64;
inline constexpr std::size_t kHeartbeatBytes = 2;
inline constexpr std::size_t kClassicBytes = 8;

enum class BusMode { kFd, kClassic };

// CANopen-style function codes; 11-bit id = base + node id (1..6).
struct ProtocolIds {
  uint32_t sample_base = 0x180;     // TPDO1: board -> host samples
  uint32_t command_base = 0x200;    // RPDO1: host -> board motor targets
  uint32_t heartbeat_base = 0x700;  // NMT heartbeat: board -> host
};

// Board status bits (sample frames and heartbeat error byte).
inline constexpr uint8_t kBoardFault = 0x01;         // any fault; motors on the board are off
inline constexpr uint8_t kBoardMotorDisabled = 0x02; // enable line low or mask bit clear
inline constexpr uint8_t kBoardOvertemp = 0x04;

struct WhiskerRaw {
  int16_t x = 0;      // Hall x, ADC counts
  int16_t y = 0;      // Hall y, ADC counts
  int16_t theta = 0;  // protraction encoder, counts
  bool fault = false;
};

// One sample of one board. seq is 16-bit in FD mode and 8-bit in classic mode.
struct BoardSample {
  int board = 0;
  uint16_t seq = 0;
  uint8_t status = 0;
  std::array<WhiskerRaw, kWhiskersPerBoard> whiskers{};
};

// Classic mode carries one whisker per frame.
struct WhiskerFragment {
  int board = 0;
  uint8_t seq = 0;
  int index = 0;  // 0..3 on the board
  uint8_t status = 0;
  WhiskerRaw whisker;
};

// CANopen NMT state of a heartbeat that announces a board's boot-up (sent once, when it starts).
constexpr uint8_t kNmtBootUp = 0x00;

struct Heartbeat {
  int board = 0;
  uint8_t state = 0;  // CANopen NMT state: 0x00 boot-up, 0x05 operational, 0x7F pre-operational, 0x04 stopped
  uint8_t error = 0;  // kBoard* bits
};

// Host -> boards: per-whisker target angles and the enable mask (bit w enables whisker w). In FD mode
// one broadcast frame carries all 24 whiskers; in classic mode one frame per board carries its 4.
struct MotorCommand {
  uint16_t seq = 0;
  uint32_t enable_mask = 0;                         // 24 bits
  std::array<int16_t, kNumWhiskers> theta_target{};  // encoder counts
};

enum class Reject {
  kNone = 0,
  kUnknownId,
  kWrongLength,
  kOutOfRange,
  kWrongFrameType,  // classic frame where FD is expected or vice versa
  kCount
};
const char* reject_name(Reject r);

enum class FrameKind { kRejected, kSample, kFragment, kHeartbeat, kCommand };

struct Decoded {
  FrameKind kind = FrameKind::kRejected;
  Reject reject = Reject::kNone;
  // Why a frame was rejected, without allocating (whiskerd decodes on its real-time thread): a
  // static phrase plus the numbers it refers to. reject_text() formats the whole sentence on demand.
  const char* reason = "";
  uint32_t id = 0;           // the rejected frame's CAN id
  int length = -1;           // kWrongLength: bytes received
  int expected_length = -1;  // kWrongLength: bytes the frame type has
  int whisker = -1;          // kOutOfRange: the offending whisker (board-local for samples), -1 = n/a
  BoardSample sample;
  WhiskerFragment fragment;
  Heartbeat heartbeat;
  MotorCommand command;
  int command_board = -1;  // classic command frames: the board whose 4 entries were decoded
};

// The reason of a rejected frame as one line, e.g. "FD sample: wrong length (24 bytes, expected 40),
// id 0x181"; "" for a frame that was not rejected. Allocates: not for the real-time path.
std::string reject_text(const Decoded& d);
// The same into `out` (always terminated, cut to fit), without allocating: for the real-time path.
// kRejectTextBytes always fits the whole line.
constexpr std::size_t kRejectTextBytes = 192;
void format_reject(const Decoded& d, std::span<char> out);

// Decodes any frame of the protocol. `fd` is whether the frame arrived as a CAN FD frame.
Decoded decode_frame(uint32_t id, bool fd, std::span<const uint8_t> data, BusMode mode,
                     const ProtocolIds& ids = {});

// Encoders return the number of bytes written (the frame length), 0 if `out` is too small.
// FD sample: one frame per board. Classic: one frame per whisker (use encode_fragment).
std::size_t encode_sample_fd(const BoardSample& s, std::span<uint8_t> out);
std::size_t encode_fragment(const WhiskerFragment& f, std::span<uint8_t> out);
std::size_t encode_heartbeat(const Heartbeat& h, std::span<uint8_t> out);
std::size_t encode_command_fd(const MotorCommand& c, std::span<uint8_t> out);
// Classic command frames have no room for seq and mask: a disabled whisker's target is
// kClassicDisabled.
inline constexpr int16_t kClassicDisabled = INT16_MIN;
std::size_t encode_command_classic(const MotorCommand& c, int board, std::span<uint8_t> out);

inline uint32_t sample_id(const ProtocolIds& ids, int board) { return ids.sample_base + board + 1; }
// FD: the broadcast command id (node 0). Classic: command_board_id per board.
inline uint32_t command_id(const ProtocolIds& ids) { return ids.command_base; }
inline uint32_t command_board_id(const ProtocolIds& ids, int board) {
  return ids.command_base + board + 1;
}
inline uint32_t heartbeat_id(const ProtocolIds& ids, int board) { return ids.heartbeat_base + board + 1; }

// One frame of a motor command as it goes on the bus. `fd`: a CAN FD frame sent with bit-rate switch;
// otherwise a classic frame.
struct CommandFrame {
  uint32_t id = 0;
  bool fd = false;
  uint8_t len = 0;
  std::array<uint8_t, kFdCommandBytes> data{};
};
// Every frame of one motor command, in the order they are sent.
struct CommandFrames {
  std::array<CommandFrame, kNumBoards> frames{};
  int count = 0;
};
// The frames that carry `c` on a bus in `mode`: FD, one broadcast frame (command_id) for all
// boards; classic, one frame per board (command_board_id), board 0 first. No allocation.
void encode_command(const MotorCommand& c, BusMode mode, const ProtocolIds& ids, CommandFrames& out);

// Counts decoded and rejected frames by reason.
struct DecodeCounters {
  int64_t frames = 0;
  std::array<int64_t, static_cast<int>(Reject::kCount)> rejected{};
  void count(const Decoded& d) {
    ++frames;
    if (d.kind == FrameKind::kRejected) ++rejected[static_cast<int>(d.reject)];
  }
  int64_t total_rejected() const {
    int64_t n = 0;
    for (auto r : rejected) n += r;
    return n;
  }
};

// Keeps the latest complete sample of each board and counts sequence gaps per board. Classic-mode
// fragments are assembled: a board sample is complete when all 4 whiskers of one seq have arrived.
// A board that reboots restarts its sequence at 0. It says so with its boot-up heartbeat, and
// restart() then takes its next sample as the start of a new sequence. Without it (the frame lost),
// the restart looks like a run of late samples when the old seq was in the lower half of the
// sequence space: after kResyncAfterLate consecutive late samples of one board (each ahead of the
// previous one, with no accepted sample in between) the last of them is accepted as the board's new
// sequence and counted in resyncs(); a single reordered frame stays late. (In the upper half, the
// restart is indistinguishable from a gap, and counted as one.)
class SampleAssembler {
 public:
  static constexpr int kResyncAfterLate = 3;

  explicit SampleAssembler(BusMode mode) : mode_(mode) {}
  // Returns true when a new complete board sample is available (latest(board)).
  bool add(const BoardSample& s);
  bool add(const WhiskerFragment& f);
  const BoardSample& latest(int board) const { return boards_[board].latest; }
  bool has_sample(int board) const { return boards_[board].have; }
  // Samples lost between consecutive received sequence numbers, per board.
  int64_t gaps(int board) const { return boards_[board].gaps; }
  int64_t total_gaps() const;
  // Fragments dropped because their sample never completed (classic mode).
  int64_t incomplete() const { return incomplete_; }
  // Samples that arrived after a newer one of their board (reordered): ignored, their seq stays a gap.
  int64_t late() const { return late_; }
  // Times a board's sequence was restarted: after its boot-up heartbeat, or after a run of late samples.
  int64_t resyncs() const { return resyncs_; }
  // The board announced its boot-up: its next sample starts a new sequence (no gap is counted to it,
  // and a half-assembled classic sample of the old one is dropped as incomplete).
  void restart(int board);
  // Count of complete samples per board since start.
  int64_t samples(int board) const { return boards_[board].samples; }

 private:
  struct Board {
    BoardSample latest;
    bool have = false;
    int64_t gaps = 0;
    int64_t samples = 0;
    BoardSample pending;
    uint8_t pending_mask = 0;
    bool pending_active = false;
    int late_run = 0;            // consecutive late samples since the last accepted one
    uint16_t last_late_seq = 0;  // seq of the last of them
    bool restarted = false;      // booted up since the latest sample: the next one starts a sequence
  };
  bool accept(Board& b, const BoardSample& s);
  BusMode mode_;
  std::array<Board, kNumBoards> boards_{};
  int64_t incomplete_ = 0;
  int64_t late_ = 0;
  int64_t resyncs_ = 0;
};

// Per-whisker calibration: deflection = R(rotation) * (gain .* (raw - offset)), theta = theta_gain *
// (raw - theta_offset). Defaults map the ADC range to -1..1 and encoder counts to radians.
struct WhiskerCalibration {
  double offset_x = 0.0, offset_y = 0.0;               // ADC counts
  double gain_x = 1.0 / kHallLimit, gain_y = 1.0 / kHallLimit;  // full scale per count
  double rotation = 0.0;                                // rad, sensor axes -> whisker axes
  double theta_offset = 0.0;                            // counts at theta = 0
  double theta_gain = kThetaRadPerCount;                // rad per count
};

struct CalibratedWhisker {
  float theta = 0.0f;
  float x = 0.0f;
  float y = 0.0f;
};

inline CalibratedWhisker calibrate(const WhiskerRaw& raw, const WhiskerCalibration& c, double cos_r,
                                   double sin_r) {
  const double dx = c.gain_x * (raw.x - c.offset_x);
  const double dy = c.gain_y * (raw.y - c.offset_y);
  return {static_cast<float>(c.theta_gain * (raw.theta - c.theta_offset)),
          static_cast<float>(cos_r * dx - sin_r * dy), static_cast<float>(sin_r * dx + cos_r * dy)};
}
CalibratedWhisker calibrate(const WhiskerRaw& raw, const WhiskerCalibration& c);

// Encoder counts for a target angle, clamped to the valid range.
int16_t theta_to_counts(double theta_rad, const WhiskerCalibration& c);

// The inverse of calibrate(): the counts a board reports for angle `theta_rad` and deflection (x, y)
// in whisker axes, rounded to the nearest count; Hall values saturate at +-kHallLimit as the ADC
// does, θ is clamped as in theta_to_counts. A zero gain maps to the offset (every count reads 0).
// Used by simulators to produce bus traffic that whiskerd calibrates back to (theta, x, y).
WhiskerRaw uncalibrate(double theta_rad, double x, double y, const WhiskerCalibration& c);

// Time one frame occupies the bus, worst-case bit stuffing, in microseconds. Classic: 11-bit id at
// `arb_bps`. FD: arbitration phase at `arb_bps`, data phase (with BRS) at `data_bps`.
double frame_time_us(BusMode mode, std::size_t data_bytes, double arb_bps, double data_bps);

struct BusLoad {
  double frames_per_s = 0;
  double busy_fraction = 0;  // 0..1 of the bus time
};
// Load of the whole protocol at `rate_hz` samples per second: samples, motor commands, heartbeats
// (10 Hz per board).
BusLoad bus_load(BusMode mode, double rate_hz, double arb_bps, double data_bps);

}  // namespace whiskeye::wp
