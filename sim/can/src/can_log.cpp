// Simulated whisker board traffic and the `candump -l` text format (see can_log.h).
#include "whiskeye/sim/can_log.h"

#include <cmath>
#include <stdexcept>

namespace whiskeye::sim {

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
    std::array<int, wp::kNumWhiskers> whisker_on{};  // channel -> whisker
    for (int w = 0; w < wp::kNumWhiskers; ++w) whisker_on[static_cast<std::size_t>(params_.channel[w])] = w;
    for (int b = 0; b < wp::kNumBoards; ++b) {
      if (board_offline(health, b)) continue;
      wp::BoardSample board;
      board.board = b;
      board.seq = seq;
      for (int k = 0; k < wp::kWhiskersPerBoard; ++k) {
        const int w = whisker_on[static_cast<std::size_t>(b * wp::kWhiskersPerBoard + k)];
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
