// Whisker CAN protocol v1: byte layouts as documented in docs/can-protocol.md (all little-endian).
#include "whiskeye/whisker_protocol/whisker_protocol.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>

namespace whiskeye::wp {
namespace {

int16_t get_i16(std::span<const uint8_t> d, std::size_t at) {
  return static_cast<int16_t>(static_cast<uint16_t>(d[at] | (d[at + 1] << 8)));
}
uint16_t get_u16(std::span<const uint8_t> d, std::size_t at) {
  return static_cast<uint16_t>(d[at] | (d[at + 1] << 8));
}
void put_u16(std::span<uint8_t> d, std::size_t at, uint16_t v) {
  d[at] = static_cast<uint8_t>(v & 0xff);
  d[at + 1] = static_cast<uint8_t>(v >> 8);
}
void put_i16(std::span<uint8_t> d, std::size_t at, int16_t v) { put_u16(d, at, static_cast<uint16_t>(v)); }

// `reason` must be a static string (Decoded::reason outlives this call).
Decoded reject(Reject r, const char* reason, uint32_t id, int whisker = -1) {
  Decoded d;
  d.kind = FrameKind::kRejected;
  d.reject = r;
  d.reason = reason;
  d.id = id;
  d.whisker = whisker;
  return d;
}

Decoded reject_length(const char* reason, uint32_t id, std::size_t got, std::size_t want) {
  Decoded d = reject(Reject::kWrongLength, reason, id);
  d.length = static_cast<int>(got);
  d.expected_length = static_cast<int>(want);
  return d;
}

bool whisker_in_range(const WhiskerRaw& w) {
  return std::abs(w.x) <= kHallLimit && std::abs(w.y) <= kHallLimit && std::abs(w.theta) <= kThetaLimit;
}

WhiskerRaw read_whisker(std::span<const uint8_t> d, std::size_t at) {
  WhiskerRaw w;
  w.x = get_i16(d, at);
  w.y = get_i16(d, at + 2);
  w.theta = get_i16(d, at + 4);
  return w;
}

void write_whisker(std::span<uint8_t> d, std::size_t at, const WhiskerRaw& w) {
  put_i16(d, at, w.x);
  put_i16(d, at + 2, w.y);
  put_i16(d, at + 4, w.theta);
}

// Node id (1..6) of `id` relative to `base`, or -1.
int board_of(uint32_t id, uint32_t base) {
  if (id <= base || id > base + kNumBoards) return -1;
  return static_cast<int>(id - base - 1);
}

}  // namespace

const char* reject_name(Reject r) {
  switch (r) {
    case Reject::kNone: return "none";
    case Reject::kUnknownId: return "unknown_id";
    case Reject::kWrongLength: return "wrong_length";
    case Reject::kOutOfRange: return "out_of_range";
    case Reject::kWrongFrameType: return "wrong_frame_type";
    case Reject::kCount: break;
  }
  return "?";
}

void format_reject(const Decoded& d, std::span<char> out) {
  if (out.empty()) return;
  out[0] = '\0';
  if (d.kind != FrameKind::kRejected) return;
  const int size = static_cast<int>(out.size());
  int n = std::snprintf(out.data(), out.size(), "%s", d.reason);
  auto add = [&](const char* fmt, auto... args) {
    if (n >= 0 && n < size) n += std::snprintf(out.data() + n, static_cast<std::size_t>(size - n), fmt, args...);
  };
  if (d.length >= 0) add(" (%d bytes, expected %d)", d.length, d.expected_length);
  add(", id 0x%03x", static_cast<unsigned>(d.id));
  if (d.whisker >= 0) add(", whisker %d", d.whisker);
}

std::string reject_text(const Decoded& d) {
  char text[kRejectTextBytes];
  format_reject(d, text);
  return text;
}

Decoded decode_frame(uint32_t id, bool fd, std::span<const uint8_t> data, BusMode mode,
                     const ProtocolIds& ids) {
  const bool want_fd = mode == BusMode::kFd;
  if (int board = board_of(id, ids.heartbeat_base); board >= 0) {
    // Heartbeats are the same in both modes and may be sent as classic frames on an FD bus.
    if (data.size() != kHeartbeatBytes) {
      return reject_length("heartbeat: wrong length", id, data.size(), kHeartbeatBytes);
    }
    Decoded d;
    d.kind = FrameKind::kHeartbeat;
    d.heartbeat = {board, data[0], data[1]};
    return d;
  }
  if (int board = board_of(id, ids.sample_base); board >= 0) {
    if (fd != want_fd) {
      return reject(Reject::kWrongFrameType,
                    fd ? "sample frame is FD on a classic bus" : "sample frame is classic on an FD bus", id);
    }
    Decoded d;
    if (want_fd) {
      if (data.size() != kFdSampleBytes) {
        return reject_length("FD sample: wrong length", id, data.size(), kFdSampleBytes);
      }
      d.kind = FrameKind::kSample;
      BoardSample& s = d.sample;
      s.board = board;
      s.seq = get_u16(data, 0);
      s.status = data[2];
      const uint8_t faults = data[3];
      for (int k = 0; k < kWhiskersPerBoard; ++k) {
        s.whiskers[k] = read_whisker(data, 4 + 6 * static_cast<std::size_t>(k));
        s.whiskers[k].fault = (faults >> k) & 1;
        if (!whisker_in_range(s.whiskers[k])) {
          return reject(Reject::kOutOfRange, "sample value out of range", id, k);
        }
      }
    } else {
      if (data.size() != kClassicBytes) {
        return reject_length("classic sample: wrong length", id, data.size(), kClassicBytes);
      }
      d.kind = FrameKind::kFragment;
      WhiskerFragment& f = d.fragment;
      f.board = board;
      f.seq = data[0];
      f.index = data[1] & 0x03;
      f.status = static_cast<uint8_t>(data[1] >> 3);
      f.whisker = read_whisker(data, 2);
      f.whisker.fault = (data[1] >> 2) & 1;
      if (!whisker_in_range(f.whisker)) {
        return reject(Reject::kOutOfRange, "sample value out of range", id, f.index);
      }
    }
    return d;
  }
  if (id >= ids.command_base && id <= ids.command_base + kNumBoards) {
    Decoded d;
    d.kind = FrameKind::kCommand;
    MotorCommand& c = d.command;
    if (want_fd) {
      if (id != ids.command_base || !fd) {
        return reject(Reject::kWrongFrameType, "command is not the FD broadcast command", id);
      }
      if (data.size() != kFdCommandBytes) {
        return reject_length("FD command: wrong length", id, data.size(), kFdCommandBytes);
      }
      c.seq = get_u16(data, 0);
      c.enable_mask = data[2] | (data[3] << 8) | (static_cast<uint32_t>(data[4]) << 16);
      for (int w = 0; w < kNumWhiskers; ++w) {
        c.theta_target[w] = get_i16(data, 6 + 2 * static_cast<std::size_t>(w));
        if (std::abs(c.theta_target[w]) > kThetaLimit) {
          return reject(Reject::kOutOfRange, "command target out of range", id, w);
        }
      }
      return d;
    }
    const int board = board_of(id, ids.command_base);
    if (board < 0 || fd) {
      return reject(Reject::kWrongFrameType, "command is not a classic per-board command", id);
    }
    if (data.size() != kClassicBytes) {
      return reject_length("classic command: wrong length", id, data.size(), kClassicBytes);
    }
    d.command_board = board;
    for (int k = 0; k < kWhiskersPerBoard; ++k) {
      const int w = board * kWhiskersPerBoard + k;
      const int16_t t = get_i16(data, 2 * static_cast<std::size_t>(k));
      if (t == kClassicDisabled) continue;
      if (std::abs(t) > kThetaLimit) {
        return reject(Reject::kOutOfRange, "command target out of range", id, w);
      }
      c.theta_target[w] = t;
      c.enable_mask |= 1u << w;
    }
    return d;
  }
  return reject(Reject::kUnknownId, "unknown CAN id", id);
}

std::size_t encode_sample_fd(const BoardSample& s, std::span<uint8_t> out) {
  if (out.size() < kFdSampleBytes) return 0;
  std::fill(out.begin(), out.begin() + kFdSampleBytes, 0);
  put_u16(out, 0, s.seq);
  out[2] = s.status;
  uint8_t faults = 0;
  for (int k = 0; k < kWhiskersPerBoard; ++k) {
    write_whisker(out, 4 + 6 * static_cast<std::size_t>(k), s.whiskers[k]);
    if (s.whiskers[k].fault) faults |= static_cast<uint8_t>(1 << k);
  }
  out[3] = faults;
  return kFdSampleBytes;
}

std::size_t encode_fragment(const WhiskerFragment& f, std::span<uint8_t> out) {
  if (out.size() < kClassicBytes) return 0;
  out[0] = f.seq;
  out[1] = static_cast<uint8_t>((f.index & 0x03) | (f.whisker.fault ? 0x04 : 0) | (f.status << 3));
  write_whisker(out, 2, f.whisker);
  return kClassicBytes;
}

std::size_t encode_heartbeat(const Heartbeat& h, std::span<uint8_t> out) {
  if (out.size() < kHeartbeatBytes) return 0;
  out[0] = h.state;
  out[1] = h.error;
  return kHeartbeatBytes;
}

std::size_t encode_command_fd(const MotorCommand& c, std::span<uint8_t> out) {
  if (out.size() < kFdCommandBytes) return 0;
  std::fill(out.begin(), out.begin() + kFdCommandBytes, 0);
  put_u16(out, 0, c.seq);
  out[2] = static_cast<uint8_t>(c.enable_mask & 0xff);
  out[3] = static_cast<uint8_t>((c.enable_mask >> 8) & 0xff);
  out[4] = static_cast<uint8_t>((c.enable_mask >> 16) & 0xff);
  for (int w = 0; w < kNumWhiskers; ++w) put_i16(out, 6 + 2 * static_cast<std::size_t>(w), c.theta_target[w]);
  return kFdCommandBytes;
}

std::size_t encode_command_classic(const MotorCommand& c, int board, std::span<uint8_t> out) {
  if (out.size() < kClassicBytes || board < 0 || board >= kNumBoards) return 0;
  for (int k = 0; k < kWhiskersPerBoard; ++k) {
    const int w = board * kWhiskersPerBoard + k;
    const bool on = (c.enable_mask >> w) & 1;
    put_i16(out, 2 * static_cast<std::size_t>(k), on ? c.theta_target[w] : kClassicDisabled);
  }
  return kClassicBytes;
}

void encode_command(const MotorCommand& c, BusMode mode, const ProtocolIds& ids, CommandFrames& out) {
  if (mode == BusMode::kFd) {
    CommandFrame& f = out.frames[0];
    f.fd = true;
    f.id = command_id(ids);
    f.len = static_cast<uint8_t>(encode_command_fd(c, f.data));
    out.count = 1;
    return;
  }
  for (int b = 0; b < kNumBoards; ++b) {
    CommandFrame& f = out.frames[static_cast<std::size_t>(b)];
    f.fd = false;
    f.id = command_board_id(ids, b);
    f.len = static_cast<uint8_t>(encode_command_classic(c, b, f.data));
  }
  out.count = kNumBoards;
}

bool SampleAssembler::accept(Board& b, const BoardSample& s) {
  if (b.have && !b.restarted) {
    const uint32_t modulus = mode_ == BusMode::kFd ? 0x10000u : 0x100u;
    auto steps = [modulus](uint16_t from, uint16_t to) {
      return (static_cast<uint32_t>(to) + modulus - from) % modulus;
    };
    const uint32_t step = steps(b.latest.seq, s.seq);
    if (step == 0) return false;  // duplicate
    if (step > modulus / 2) {
      // A step in the upper half of the sequence space is a late (reordered) frame, not a gap —
      // unless it starts a run of them that advances by itself: the board restarted its sequence.
      const uint32_t run_step = steps(b.last_late_seq, s.seq);
      const bool continues = b.late_run > 0 && run_step > 0 && run_step <= modulus / 2;
      b.late_run = continues ? b.late_run + 1 : 1;
      b.last_late_seq = s.seq;
      if (b.late_run < kResyncAfterLate) {
        ++late_;
        return false;
      }
      ++resyncs_;  // follow the new sequence; the samples skipped in the run are not gaps
    } else {
      b.gaps += step - 1;
    }
  }
  b.late_run = 0;
  b.restarted = false;
  b.latest = s;
  b.have = true;
  ++b.samples;
  return true;
}

void SampleAssembler::restart(int board) {
  if (board < 0 || board >= kNumBoards) return;
  Board& b = boards_[board];
  if (b.pending_active) ++incomplete_;
  b.pending_active = false;
  b.late_run = 0;
  if (b.have) {
    ++resyncs_;         // a board seen before started over (its first boot is no restart)
    b.restarted = true;  // its next sample is the first of the new sequence: no step, no gap
  }
}

bool SampleAssembler::add(const BoardSample& s) {
  if (s.board < 0 || s.board >= kNumBoards) return false;
  return accept(boards_[s.board], s);
}

bool SampleAssembler::add(const WhiskerFragment& f) {
  if (f.board < 0 || f.board >= kNumBoards) return false;
  Board& b = boards_[f.board];
  if (b.pending_active && b.pending.seq != f.seq) {
    ++incomplete_;  // the previous sample lost a fragment
    b.pending_active = false;
  }
  if (!b.pending_active) {
    b.pending = BoardSample{};
    b.pending.board = f.board;
    b.pending.seq = f.seq;
    b.pending_mask = 0;
    b.pending_active = true;
  }
  b.pending.whiskers[f.index] = f.whisker;
  b.pending.status |= f.status;
  b.pending_mask |= static_cast<uint8_t>(1 << f.index);
  if (b.pending_mask != 0x0f) return false;
  b.pending_active = false;
  return accept(b, b.pending);
}

int64_t SampleAssembler::total_gaps() const {
  int64_t n = 0;
  for (const auto& b : boards_) n += b.gaps;
  return n;
}

CalibratedWhisker calibrate(const WhiskerRaw& raw, const WhiskerCalibration& c) {
  return calibrate(raw, c, std::cos(c.rotation), std::sin(c.rotation));
}

int16_t theta_to_counts(double theta_rad, const WhiskerCalibration& c) {
  const double counts = std::round(theta_rad / c.theta_gain + c.theta_offset);
  return static_cast<int16_t>(std::clamp(counts, -static_cast<double>(kThetaLimit), static_cast<double>(kThetaLimit)));
}

WhiskerRaw uncalibrate(double theta_rad, double x, double y, const WhiskerCalibration& c) {
  // Whisker axes -> sensor axes: R(-rotation).
  const double cr = std::cos(c.rotation), sr = std::sin(c.rotation);
  const double sx = cr * x + sr * y;
  const double sy = -sr * x + cr * y;
  auto hall = [](double v, double gain, double offset) {
    const double counts = gain == 0.0 ? offset : std::round(v / gain + offset);
    const double limit = kHallLimit;
    return static_cast<int16_t>(std::clamp(counts, -limit, limit));
  };
  WhiskerRaw raw;
  raw.x = hall(sx, c.gain_x, c.offset_x);
  raw.y = hall(sy, c.gain_y, c.offset_y);
  raw.theta = theta_to_counts(theta_rad, c);
  return raw;
}

double frame_time_us(BusMode mode, std::size_t n, double arb_bps, double data_bps) {
  const double data_bits = 8.0 * static_cast<double>(n);
  if (mode == BusMode::kClassic) {
    // SOF..CRC (34 + 8n bits) is stuffed: worst case one stuff bit per 4 after the first.
    const double stuffed = 34.0 + data_bits;
    const double bits = stuffed + std::floor((stuffed - 1.0) / 4.0) + 13.0;  // + CRC del, ACK, EOF, IFS
    return bits / arb_bps * 1e6;
  }
  // FD, 11-bit id, BRS. Nominal rate: SOF..BRS (17 bits, worst-case stuffing 4) and CRC delimiter,
  // ACK, ACK delimiter, EOF, IFS (13 bits). Data rate: ESI, DLC, data (dynamically stuffed), stuff
  // count (4) and CRC (17 or 21 bits) with a fixed stuff bit every 4 bits.
  const double nominal = 17.0 + 4.0 + 13.0;
  const double crc = n > 16 ? 21.0 : 17.0;
  const double dyn = 5.0 + data_bits;
  const double fast = dyn + std::floor(dyn / 4.0) + 4.0 + crc + std::ceil((crc + 4.0) / 4.0);
  return nominal / arb_bps * 1e6 + fast / data_bps * 1e6;
}

BusLoad bus_load(BusMode mode, double rate_hz, double arb_bps, double data_bps) {
  double frames = 0, busy_us = 0;
  auto add = [&](double per_s, std::size_t bytes, BusMode m) {
    frames += per_s;
    busy_us += per_s * frame_time_us(m, bytes, arb_bps, data_bps);
  };
  if (mode == BusMode::kFd) {
    add(rate_hz * kNumBoards, kFdSampleBytes, BusMode::kFd);
    add(rate_hz, kFdCommandBytes, BusMode::kFd);
  } else {
    add(rate_hz * kNumWhiskers, kClassicBytes, BusMode::kClassic);
    add(rate_hz * kNumBoards, kClassicBytes, BusMode::kClassic);
  }
  add(kHeartbeatHz * kNumBoards, kHeartbeatBytes, BusMode::kClassic);
  return {frames, busy_us / 1e6};
}

}  // namespace whiskeye::wp
