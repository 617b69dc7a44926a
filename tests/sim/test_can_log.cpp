// The simulated whisker boards' CAN traffic: the candump -l line format, frame rates, sequence
// counters, quantisation and saturation, decoded with the real protocol decoder.
#include "whiskeye/sim/can_log.h"

#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <random>
#include <sstream>

namespace whiskeye::sim {
namespace {

constexpr int64_t kStart = 1'700'000'000'000'000;

rcp::WhiskerSample sample_at(int64_t i, std::mt19937& rng) {
  // Within the Hall range after any rotation and the test calibrations' gains and offsets.
  std::uniform_real_distribution<double> u(-0.6, 0.6);
  rcp::WhiskerSample s;
  s.utime = kStart + 2000 * i;
  s.seq = i;
  for (int w = 0; w < rcp::kNumWhiskers; ++w) {
    s.theta[w] = u(rng);
    s.deflection_x[w] = u(rng);
    s.deflection_y[w] = u(rng);
    s.valid[w] = true;
  }
  return s;
}

// 500 Hz samples for `n` periods through BoardTraffic.
std::vector<CanFrame> traffic(const BoardTrafficParams& p, int n, std::vector<rcp::WhiskerSample>* samples = nullptr) {
  BoardTraffic t(p);
  std::mt19937 rng(3);
  std::vector<CanFrame> frames;
  for (int i = 0; i < n; ++i) {
    const rcp::WhiskerSample s = sample_at(i, rng);
    if (samples) samples->push_back(s);
    t.add(s, WhiskerHealth{}, frames);
  }
  return frames;
}

TEST(CandumpLine, FormatsFdAndClassicFramesLikeCandumpLog) {
  CanFrame fd{1'700'000'000'002'000, 0x181, true, kCanFdBrs, {0x00, 0x01, 0xAB, 0xfe}};
  EXPECT_EQ(format_candump_line(fd, "can0"), "(1700000000.002000) can0 181##10001ABFE");
  CanFrame classic{12'345'678, 0x701, false, 0, {0x05, 0x00}};
  EXPECT_EQ(format_candump_line(classic, "vcan1"), "(0000000012.345678) vcan1 701#0500");
  CanFrame empty{0, 0x7, false, 0, {}};
  EXPECT_EQ(format_candump_line(empty, "can0"), "(0000000000.000000) can0 007#");
}

TEST(CandumpLine, ParsesWhatItFormatsAndRejectsOtherText) {
  std::vector<uint8_t> data(32);
  for (std::size_t i = 0; i < data.size(); ++i) data[i] = static_cast<uint8_t>(i * 37);
  const CanFrame in{1'700'000'123'456'789, 0x186, true, kCanFdBrs, data};
  CanFrame out;
  std::string iface;
  ASSERT_TRUE(parse_candump_line(format_candump_line(in, "can0"), out, iface));
  EXPECT_EQ(iface, "can0");
  EXPECT_EQ(out.utime, in.utime);
  EXPECT_EQ(out.id, in.id);
  EXPECT_TRUE(out.fd);
  EXPECT_EQ(out.fd_flags, kCanFdBrs);
  EXPECT_EQ(out.data, in.data);
  ASSERT_TRUE(parse_candump_line("(1.000001) can0 701#0500", out, iface));
  EXPECT_FALSE(out.fd);
  EXPECT_EQ(out.utime, 1'000'001);
  EXPECT_EQ(out.data, (std::vector<uint8_t>{5, 0}));
  for (const char* bad : {"", "1.000000 can0 701#0500", "(1.000000) can0 701#050", "(1.000000) can0 701#05G0",
                          "(1.00000) can0 701#0500", "(1.000000) can0 12345678#00", "(1.000000) can0 181##1" "000000000000000000" /* 9 bytes: no FD length */,
                          "(1.000000) can0 701#000000000000000000", "(1.000000) can0 701R"}) {
    EXPECT_FALSE(parse_candump_line(bad, out, iface)) << bad;
  }
}

TEST(BoardTraffic, FdSendsOne32ByteFramePerBoardPerSampleAndHeartbeatsAt10Hz) {
  BoardTrafficParams p;
  const std::vector<CanFrame> frames = traffic(p, 250);  // 0.5 s at 500 Hz
  std::map<uint32_t, std::vector<int64_t>> times;
  for (const CanFrame& f : frames) {
    times[f.id].push_back(f.utime);
    if (f.id >= 0x181 && f.id <= 0x186) {
      EXPECT_TRUE(f.fd);
      EXPECT_EQ(f.fd_flags, kCanFdBrs);
      EXPECT_EQ(f.data.size(), wp::kFdSampleBytes);
    } else {
      EXPECT_FALSE(f.fd);
      EXPECT_EQ(f.data.size(), wp::kHeartbeatBytes);
    }
  }
  ASSERT_EQ(times.size(), 12u) << "six sample ids and six heartbeat ids";
  for (int b = 0; b < 6; ++b) {
    const auto& s = times[0x181u + b];
    ASSERT_EQ(s.size(), 250u);
    for (std::size_t i = 1; i < s.size(); ++i) EXPECT_EQ(s[i] - s[i - 1], 2000);
    const auto& h = times[0x701u + b];
    ASSERT_EQ(h.size(), 5u);
    for (std::size_t i = 1; i < h.size(); ++i) EXPECT_EQ(h[i] - h[i - 1], 100000);
  }
  for (std::size_t i = 1; i < frames.size(); ++i) EXPECT_LE(frames[i - 1].utime, frames[i].utime);
}

TEST(BoardTraffic, ClassicSendsFourFramesPerBoardAt100HzInWhiskerOrder) {
  BoardTrafficParams p;
  p.mode = wp::BusMode::kClassic;
  p.rate_hz = 100.0;
  const std::vector<CanFrame> frames = traffic(p, 250);
  std::map<uint32_t, std::vector<const CanFrame*>> by_id;
  for (const CanFrame& f : frames) {
    EXPECT_FALSE(f.fd);
    by_id[f.id].push_back(&f);
  }
  for (int b = 0; b < 6; ++b) {
    const auto& s = by_id[0x181u + b];
    ASSERT_EQ(s.size(), 50u * 4);
    for (std::size_t i = 0; i < s.size(); ++i) {
      EXPECT_EQ(s[i]->data.size(), 8u);
      EXPECT_EQ(s[i]->utime, kStart + 10000 * static_cast<int64_t>(i / 4));
      EXPECT_EQ(s[i]->data[1] & 0x03, static_cast<int>(i % 4)) << "whisker index on the board";
      EXPECT_EQ(s[i]->data[0], static_cast<uint8_t>(i / 4)) << "8-bit seq";
    }
    EXPECT_EQ(by_id[0x701u + b].size(), 5u);
  }
}

// Decodes frames with the protocol decoder and assembles them as whiskerd does.
struct Decoded {
  wp::SampleAssembler assembler;
  std::vector<std::array<wp::BoardSample, wp::kNumBoards>> samples;  // one per complete sample time
  std::array<wp::BoardSample, wp::kNumBoards> current{};
  int heartbeats = 0;
  int64_t rejected = 0;
  explicit Decoded(wp::BusMode mode) : assembler(mode) {}
  void feed(const std::vector<CanFrame>& frames, wp::BusMode mode) {
    for (const CanFrame& f : frames) {
      const wp::Decoded d = wp::decode_frame(f.id, f.fd, f.data, mode);
      bool complete = false;
      int board = -1;
      switch (d.kind) {
        case wp::FrameKind::kSample:
          complete = assembler.add(d.sample);
          board = d.sample.board;
          break;
        case wp::FrameKind::kFragment:
          complete = assembler.add(d.fragment);
          board = d.fragment.board;
          break;
        case wp::FrameKind::kHeartbeat:
          ++heartbeats;
          EXPECT_EQ(d.heartbeat.state, 0x05);
          break;
        default:
          ++rejected;
          ADD_FAILURE() << wp::reject_text(d);
      }
      if (complete) {
        current[board] = assembler.latest(board);
        if (board == wp::kNumBoards - 1) samples.push_back(current);
      }
    }
  }
};

void expect_calibrates_back(const std::vector<rcp::WhiskerSample>& truth, const Decoded& dec, int every,
                            const BoardTrafficParams& p) {
  ASSERT_EQ(dec.samples.size(), (truth.size() + every - 1) / every);
  for (std::size_t i = 0; i < dec.samples.size(); ++i) {
    const rcp::WhiskerSample& s = truth[i * every];
    for (int w = 0; w < wp::kNumWhiskers; ++w) {
      const wp::WhiskerCalibration& c = p.calibration[w];
      const wp::WhiskerRaw& raw = dec.samples[i][w / 4].whiskers[w % 4];
      const wp::CalibratedWhisker back = wp::calibrate(raw, c);
      // One count through the gains and the rotation (rounding is half a count per axis).
      const double step = std::abs(c.gain_x) + std::abs(c.gain_y);
      EXPECT_NEAR(back.theta, s.theta[w], std::abs(c.theta_gain)) << "sample " << i << " whisker " << w;
      EXPECT_NEAR(back.x, s.deflection_x[w], step) << "sample " << i << " whisker " << w;
      EXPECT_NEAR(back.y, s.deflection_y[w], step) << "sample " << i << " whisker " << w;
      EXPECT_FALSE(raw.fault);
    }
  }
}

BoardTrafficParams with_calibration(BoardTrafficParams p) {
  for (int w = 0; w < wp::kNumWhiskers; ++w) {
    wp::WhiskerCalibration& c = p.calibration[w];
    c.offset_x = 3 * w - 30;
    c.offset_y = 20 - w;
    c.gain_x = 1.0 / (1800 + 10 * w);
    c.gain_y = 1.0 / (1900 - 5 * w);
    c.rotation = 0.05 * w - 0.6;
    c.theta_offset = w - 12;
  }
  return p;
}

TEST(BoardTraffic, FdFramesDecodeAndCalibrateBackToTheSamplesWithinOneCount) {
  const BoardTrafficParams p = with_calibration({});
  std::vector<rcp::WhiskerSample> truth;
  const std::vector<CanFrame> frames = traffic(p, 300, &truth);
  Decoded dec(wp::BusMode::kFd);
  dec.feed(frames, wp::BusMode::kFd);
  expect_calibrates_back(truth, dec, 1, p);
  EXPECT_EQ(dec.heartbeats, 6 * 6);
  EXPECT_EQ(dec.assembler.total_gaps(), 0);
}

TEST(BoardTraffic, ClassicFragmentsAssembleAndCalibrateBackWithinOneCount) {
  BoardTrafficParams p;
  p.mode = wp::BusMode::kClassic;
  p.rate_hz = 100.0;
  p = with_calibration(p);
  std::vector<rcp::WhiskerSample> truth;
  const std::vector<CanFrame> frames = traffic(p, 300, &truth);
  Decoded dec(wp::BusMode::kClassic);
  dec.feed(frames, wp::BusMode::kClassic);
  expect_calibrates_back(truth, dec, 5, p);
  EXPECT_EQ(dec.assembler.incomplete(), 0);
  EXPECT_EQ(dec.assembler.total_gaps(), 0);
}

TEST(BoardTraffic, SequenceCountersWrapAt65536InFdAnd256InClassic) {
  BoardTrafficParams fd;
  fd.first_seq = 65533;
  std::vector<uint16_t> seqs;
  for (const CanFrame& f : traffic(fd, 6)) {
    if (f.id == 0x183) seqs.push_back(static_cast<uint16_t>(f.data[0] | f.data[1] << 8));
  }
  EXPECT_EQ(seqs, (std::vector<uint16_t>{65533, 65534, 65535, 0, 1, 2}));

  BoardTrafficParams classic;
  classic.mode = wp::BusMode::kClassic;
  classic.rate_hz = 100.0;
  const std::vector<CanFrame> frames = traffic(classic, 5 * 260);  // 260 samples, past the 8-bit wrap
  Decoded dec(wp::BusMode::kClassic);
  dec.feed(frames, wp::BusMode::kClassic);
  EXPECT_EQ(dec.samples.size(), 260u);
  EXPECT_EQ(dec.assembler.total_gaps(), 0) << "the wrap 255 -> 0 is no gap";
  EXPECT_EQ(dec.assembler.late(), 0);
  EXPECT_EQ(dec.assembler.latest(0).seq, 259 % 256);
}

TEST(BoardTraffic, LargeDeflectionsSaturateAt2047AndInvalidWhiskersCarryTheFaultBit) {
  BoardTrafficParams p;
  BoardTraffic t(p);
  rcp::WhiskerSample s;
  s.utime = kStart;
  s.valid.fill(true);
  s.deflection_x[0] = 1.7;
  s.deflection_y[0] = -2.5;
  s.theta[1] = 2.0;  // beyond the encoder's +-90 deg range
  s.valid[6] = false;
  std::vector<CanFrame> frames;
  t.add(s, WhiskerHealth{}, frames);
  ASSERT_GE(frames.size(), 2u);
  const wp::Decoded b0 = wp::decode_frame(frames[0].id, true, frames[0].data, wp::BusMode::kFd);
  ASSERT_EQ(b0.kind, wp::FrameKind::kSample) << wp::reject_text(b0);
  EXPECT_EQ(b0.sample.whiskers[0].x, wp::kHallLimit);
  EXPECT_EQ(b0.sample.whiskers[0].y, -wp::kHallLimit);
  EXPECT_EQ(b0.sample.whiskers[1].theta, wp::kThetaLimit);
  const wp::Decoded b1 = wp::decode_frame(frames[1].id, true, frames[1].data, wp::BusMode::kFd);
  ASSERT_EQ(b1.kind, wp::FrameKind::kSample);
  EXPECT_TRUE(b1.sample.whiskers[2].fault);
  EXPECT_FALSE(b1.sample.whiskers[1].fault);
}

TEST(CandumpWriter, WritesOneLinePerFrameOnTheGivenInterface) {
  std::ostringstream out;
  BoardTrafficParams p;
  CandumpWriter writer(out, p, "vcan3");
  std::mt19937 rng(1);
  for (int i = 0; i < 60; ++i) writer.whisker_sample(sample_at(i, rng), WhiskerHealth{});
  EXPECT_EQ(writer.frames_written(), 60 * 6 + 6 * 2);
  EXPECT_EQ(writer.samples_sent(), 60);
  std::istringstream in(out.str());
  std::string line;
  std::string iface;
  CanFrame f;
  int n = 0;
  while (std::getline(in, line)) {
    ASSERT_TRUE(parse_candump_line(line, f, iface)) << line;
    EXPECT_EQ(iface, "vcan3");
    ++n;
  }
  EXPECT_EQ(n, writer.frames_written());
}

}  // namespace
}  // namespace whiskeye::sim
