// Simulated whisker board traffic and the `candump -l` text format (see can_log.h).
#include "whiskeye/sim/can_log.h"

#include <cmath>
#include <cstdio>
#include <stdexcept>

namespace whiskeye::sim {

namespace {

constexpr char kHex[] = "0123456789ABCDEF";

int hex_value(char c) {
  if (c >= '0' && c <= '9') return c - '0';
  if (c >= 'A' && c <= 'F') return c - 'A' + 10;
  if (c >= 'a' && c <= 'f') return c - 'a' + 10;
  return -1;
}

// Parses all of `s` as an unsigned decimal number.
bool parse_decimal(std::string_view s, int64_t& v) {
  if (s.empty() || s.size() > 18) return false;
  v = 0;
  for (char c : s) {
    if (c < '0' || c > '9') return false;
    v = v * 10 + (c - '0');
  }
  return true;
}

bool valid_fd_length(std::size_t n) {
  return n <= 8 || n == 12 || n == 16 || n == 20 || n == 24 || n == 32 || n == 48 || n == 64;
}

}  // namespace

std::string format_candump_line(const CanFrame& f, std::string_view interface) {
  // candump's log format: "(%010lu.%06lu) %s %03X#..." (see `man candump`, -l).
  const int64_t sec = f.utime / 1000000;
  const int64_t usec = f.utime % 1000000;
  char stamp[48];
  std::snprintf(stamp, sizeof stamp, "(%010lld.%06lld) ", static_cast<long long>(sec), static_cast<long long>(usec));
  std::string line(stamp);
  line.append(interface);
  line += ' ';
  line += kHex[(f.id >> 8) & 0xf];
  line += kHex[(f.id >> 4) & 0xf];
  line += kHex[f.id & 0xf];
  line += '#';
  if (f.fd) {
    line += '#';
    line += kHex[f.fd_flags & 0xf];
  }
  for (uint8_t b : f.data) {
    line += kHex[b >> 4];
    line += kHex[b & 0xf];
  }
  return line;
}

bool parse_candump_line(std::string_view line, CanFrame& f, std::string& interface) {
  if (line.size() < 4 || line.front() != '(') return false;
  const std::size_t close = line.find(") ");
  const std::size_t dot = line.find('.');
  if (close == std::string_view::npos || dot == std::string_view::npos || dot > close) return false;
  int64_t sec = 0, usec = 0;
  const std::string_view frac = line.substr(dot + 1, close - dot - 1);
  if (!parse_decimal(line.substr(1, dot - 1), sec) || frac.size() != 6 || !parse_decimal(frac, usec)) return false;
  f.utime = sec * 1000000 + usec;
  std::string_view rest = line.substr(close + 2);
  const std::size_t space = rest.find(' ');
  if (space == 0 || space == std::string_view::npos) return false;
  interface.assign(rest.substr(0, space));
  rest = rest.substr(space + 1);
  const std::size_t hash = rest.find('#');
  if (hash != 3) return false;  // standard (11-bit) ids only
  f.id = 0;
  for (std::size_t i = 0; i < 3; ++i) {
    const int v = hex_value(rest[i]);
    if (v < 0) return false;
    f.id = f.id << 4 | static_cast<uint32_t>(v);
  }
  if (f.id > 0x7ff) return false;
  rest = rest.substr(4);
  f.fd = !rest.empty() && rest.front() == '#';
  f.fd_flags = 0;
  if (f.fd) {
    if (rest.size() < 2 || hex_value(rest[1]) < 0) return false;
    f.fd_flags = static_cast<uint8_t>(hex_value(rest[1]));
    rest = rest.substr(2);
  }
  if (rest.size() % 2 != 0) return false;
  f.data.clear();
  for (std::size_t i = 0; i < rest.size(); i += 2) {
    const int hi = hex_value(rest[i]);
    const int lo = hex_value(rest[i + 1]);
    if (hi < 0 || lo < 0) return false;
    f.data.push_back(static_cast<uint8_t>(hi << 4 | lo));
  }
  return f.fd ? valid_fd_length(f.data.size()) : f.data.size() <= 8;
}

BoardTraffic::BoardTraffic(const BoardTrafficParams& params)
    : params_(params),
      sample_period_us_(params.rate_hz > 0 ? std::llround(1e6 / params.rate_hz) : 0),
      heartbeat_period_us_(params.heartbeat_hz > 0 ? std::llround(1e6 / params.heartbeat_hz) : 0) {
  if (sample_period_us_ <= 0 || heartbeat_period_us_ <= 0) {
    throw std::invalid_argument("board sample and heartbeat rates must be positive");
  }
}

namespace {

// A board is offline when the simulator marks its whiskers stale (it marks a whole board at once).
bool board_offline(const WhiskerHealth& health, int board) {
  return health.stale[static_cast<std::size_t>(board * wp::kWhiskersPerBoard)];
}

}  // namespace

void BoardTraffic::add(const rcp::WhiskerSample& s, const WhiskerHealth& health, std::vector<CanFrame>& out) {
  if (!started_) {
    started_ = true;
    next_sample_utime_ = s.utime;
    next_heartbeat_utime_ = s.utime;
  }
  if (s.utime >= next_sample_utime_) {
    next_sample_utime_ += sample_period_us_;
    // Wraps as documented: 16 bits in FD mode, 8 bits in classic mode (the cast truncates).
    const auto seq = static_cast<uint16_t>(params_.first_seq + samples_sent_);
    ++samples_sent_;
    for (int b = 0; b < wp::kNumBoards; ++b) {
      if (board_offline(health, b)) continue;
      wp::BoardSample board;
      board.board = b;
      board.seq = seq;
      for (int k = 0; k < wp::kWhiskersPerBoard; ++k) {
        const int w = b * wp::kWhiskersPerBoard + k;
        wp::WhiskerRaw& raw = board.whiskers[k];
        raw = wp::uncalibrate(s.theta[w], s.deflection_x[w], s.deflection_y[w], params_.calibration[w]);
        raw.fault = health.fault[w] || !s.valid[w];
      }
      if (params_.mode == wp::BusMode::kFd) {
        CanFrame& f = out.emplace_back();
        f.utime = s.utime;
        f.id = wp::sample_id(params_.ids, b);
        f.fd = true;
        f.fd_flags = kCanFdBrs;
        f.data.resize(wp::kFdSampleBytes);
        wp::encode_sample_fd(board, f.data);
      } else {
        // A board sends its four whisker frames of one sample in order k = 0..3.
        for (int k = 0; k < wp::kWhiskersPerBoard; ++k) {
          const wp::WhiskerFragment frag{b, static_cast<uint8_t>(seq), k, board.status, board.whiskers[k]};
          CanFrame& f = out.emplace_back();
          f.utime = s.utime;
          f.id = wp::sample_id(params_.ids, b);
          f.data.resize(wp::kClassicBytes);
          wp::encode_fragment(frag, f.data);
        }
      }
    }
  }
  if (s.utime >= next_heartbeat_utime_) {
    next_heartbeat_utime_ += heartbeat_period_us_;
    for (int b = 0; b < wp::kNumBoards; ++b) {
      if (board_offline(health, b)) continue;
      CanFrame& f = out.emplace_back();
      f.utime = s.utime;
      f.id = wp::heartbeat_id(params_.ids, b);
      f.data.resize(wp::kHeartbeatBytes);
      wp::encode_heartbeat({b, params_.nmt_state, 0}, f.data);
    }
  }
}

CandumpWriter::CandumpWriter(std::ostream& out, const BoardTrafficParams& params, std::string interface)
    : out_(out), traffic_(params), interface_(std::move(interface)) {}

void CandumpWriter::whisker_sample(const rcp::WhiskerSample& sample, const WhiskerHealth& health) {
  frames_.clear();
  traffic_.add(sample, health, frames_);
  for (const CanFrame& f : frames_) {
    out_ << format_candump_line(f, interface_) << '\n';
    ++frames_written_;
  }
}

}  // namespace whiskeye::sim
