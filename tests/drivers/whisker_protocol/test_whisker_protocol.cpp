// Whisker CAN protocol codec, sample assembler, calibration and bus-load figures (no bus needed).
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <random>
#include <vector>

#include "whiskeye/whisker_protocol/whisker_protocol.h"

using namespace whiskeye::wp;

namespace {

BoardSample make_sample(int board, uint16_t seq) {
  BoardSample s;
  s.board = board;
  s.seq = seq;
  s.status = kBoardMotorDisabled;
  for (int k = 0; k < kWhiskersPerBoard; ++k) {
    s.whiskers[k] = {static_cast<int16_t>(100 * k - 150), static_cast<int16_t>(-7 * k), static_cast<int16_t>(300 - k), k == 2};
  }
  return s;
}

}  // namespace

TEST(WhiskerProtocol, FdSampleRoundTrips) {
  std::array<uint8_t, 64> buf{};
  const BoardSample in = make_sample(3, 0xBEEF);
  ASSERT_EQ(encode_sample_fd(in, buf), kFdSampleBytes);
  const Decoded d = decode_frame(0x184, true, std::span(buf.data(), kFdSampleBytes), BusMode::kFd);
  ASSERT_EQ(d.kind, FrameKind::kSample) << d.reason;
  EXPECT_EQ(d.sample.board, 3);
  EXPECT_EQ(d.sample.seq, 0xBEEF);
  EXPECT_EQ(d.sample.status, kBoardMotorDisabled);
  for (int k = 0; k < kWhiskersPerBoard; ++k) {
    EXPECT_EQ(d.sample.whiskers[k].x, in.whiskers[k].x);
    EXPECT_EQ(d.sample.whiskers[k].y, in.whiskers[k].y);
    EXPECT_EQ(d.sample.whiskers[k].theta, in.whiskers[k].theta);
    EXPECT_EQ(d.sample.whiskers[k].fault, k == 2);
  }
}

TEST(WhiskerProtocol, FdSampleLayoutIsLittleEndianAsDocumented) {
  std::array<uint8_t, 32> buf{};
  BoardSample s;
  s.seq = 0x0102;
  s.whiskers[0] = {0x0304, -2, 5, false};
  encode_sample_fd(s, buf);
  EXPECT_EQ(buf[0], 0x02);
  EXPECT_EQ(buf[1], 0x01);
  EXPECT_EQ(buf[4], 0x04);
  EXPECT_EQ(buf[5], 0x03);
  EXPECT_EQ(buf[6], 0xFE);
  EXPECT_EQ(buf[7], 0xFF);
  EXPECT_EQ(buf[8], 5);
}

TEST(WhiskerProtocol, RejectsTruncatedFrame) {
  std::array<uint8_t, 32> buf{};
  encode_sample_fd(make_sample(0, 1), buf);
  const Decoded d = decode_frame(0x181, true, std::span(buf.data(), 24), BusMode::kFd);
  EXPECT_EQ(d.kind, FrameKind::kRejected);
  EXPECT_EQ(d.reject, Reject::kWrongLength);
  EXPECT_NE(reject_text(d).find("24 bytes, expected 32"), std::string::npos) << reject_text(d);
}

TEST(WhiskerProtocol, RejectsUnknownId) {
  std::array<uint8_t, 32> buf{};
  for (uint32_t id : {0x180u, 0x187u, 0x555u, 0x700u}) {
    const Decoded d = decode_frame(id, true, buf, BusMode::kFd);
    EXPECT_EQ(d.reject, Reject::kUnknownId) << std::hex << id;
    EXPECT_NE(reject_text(d).find("unknown CAN id"), std::string::npos) << reject_text(d);
  }
}

TEST(WhiskerProtocol, RejectsOutOfRangeHallAndEncoderValues) {
  std::array<uint8_t, 32> buf{};
  BoardSample s = make_sample(1, 5);
  s.whiskers[1].x = 3000;
  encode_sample_fd(s, buf);
  EXPECT_EQ(decode_frame(0x182, true, buf, BusMode::kFd).reject, Reject::kOutOfRange);
  EXPECT_EQ(reject_text(decode_frame(0x182, true, buf, BusMode::kFd)),
            "sample value out of range, id 0x182, whisker 1");
  s = make_sample(1, 5);
  s.whiskers[3].theta = -2000;
  encode_sample_fd(s, buf);
  EXPECT_EQ(decode_frame(0x182, true, buf, BusMode::kFd).reject, Reject::kOutOfRange);
  s.whiskers[3].theta = -kThetaLimit;
  encode_sample_fd(s, buf);
  EXPECT_EQ(decode_frame(0x182, true, buf, BusMode::kFd).kind, FrameKind::kSample);
}

TEST(WhiskerProtocol, RejectsClassicSampleOnFdBus) {
  std::array<uint8_t, 8> buf{};
  const Decoded d = decode_frame(0x181, false, buf, BusMode::kFd);
  EXPECT_EQ(d.reject, Reject::kWrongFrameType);
  EXPECT_EQ(reject_text(d), "sample frame is classic on an FD bus, id 0x181");
}

TEST(WhiskerProtocol, AcceptedFrameHasNoRejectText) {
  std::array<uint8_t, 32> buf{};
  encode_sample_fd(make_sample(0, 1), buf);
  const Decoded d = decode_frame(0x181, true, buf, BusMode::kFd);
  ASSERT_EQ(d.kind, FrameKind::kSample);
  EXPECT_EQ(reject_text(d), "");
}

TEST(WhiskerProtocol, ConfigurableIdsAreHonoured) {
  ProtocolIds ids;
  ids.sample_base = 0x300;
  std::array<uint8_t, 32> buf{};
  encode_sample_fd(make_sample(5, 9), buf);
  EXPECT_EQ(decode_frame(0x306, true, buf, BusMode::kFd, ids).kind, FrameKind::kSample);
  EXPECT_EQ(decode_frame(0x186, true, buf, BusMode::kFd, ids).reject, Reject::kUnknownId);
}

TEST(WhiskerProtocol, HeartbeatDecodes) {
  std::array<uint8_t, 2> buf{};
  encode_heartbeat({4, 0x05, kBoardFault}, buf);
  const Decoded d = decode_frame(0x705, false, buf, BusMode::kFd);
  ASSERT_EQ(d.kind, FrameKind::kHeartbeat);
  EXPECT_EQ(d.heartbeat.board, 4);
  EXPECT_EQ(d.heartbeat.state, 0x05);
  EXPECT_EQ(d.heartbeat.error, kBoardFault);
}

TEST(WhiskerProtocol, FdCommandRoundTripsWithEnableMask) {
  MotorCommand c;
  c.seq = 77;
  c.enable_mask = 0xA5A5A5;
  for (int w = 0; w < kNumWhiskers; ++w) c.theta_target[w] = static_cast<int16_t>(40 * w - 500);
  std::array<uint8_t, 64> buf{};
  ASSERT_EQ(encode_command_fd(c, buf), kFdCommandBytes);
  const Decoded d = decode_frame(0x200, true, buf, BusMode::kFd);
  ASSERT_EQ(d.kind, FrameKind::kCommand) << d.reason;
  EXPECT_EQ(d.command.seq, 77);
  EXPECT_EQ(d.command.enable_mask, 0xA5A5A5u);
  EXPECT_EQ(d.command.theta_target, c.theta_target);
}

TEST(WhiskerProtocol, ClassicCommandMarksDisabledWhiskers) {
  MotorCommand c;
  c.enable_mask = 0b1011u << 8;  // board 2: whiskers 8, 9, 11
  c.theta_target[8] = 10;
  c.theta_target[9] = -20;
  c.theta_target[10] = 30;
  c.theta_target[11] = 40;
  std::array<uint8_t, 8> buf{};
  ASSERT_EQ(encode_command_classic(c, 2, buf), kClassicBytes);
  const Decoded d = decode_frame(0x203, false, buf, BusMode::kClassic);
  ASSERT_EQ(d.kind, FrameKind::kCommand) << d.reason;
  EXPECT_EQ(d.command_board, 2);
  EXPECT_EQ(d.command.enable_mask, c.enable_mask);
  EXPECT_EQ(d.command.theta_target[9], -20);
  EXPECT_EQ(d.command.theta_target[10], 0);
}

TEST(WhiskerProtocol, CommandOnFdIsOneBroadcastFrameWithBitRateSwitch) {
  MotorCommand c;
  c.seq = 9;
  c.enable_mask = 0xFFFFFF;
  c.theta_target[23] = -123;
  ProtocolIds ids;
  ids.command_base = 0x300;
  CommandFrames out;
  encode_command(c, BusMode::kFd, ids, out);
  ASSERT_EQ(out.count, 1);
  const CommandFrame& f = out.frames[0];
  EXPECT_TRUE(f.fd);
  EXPECT_EQ(f.id, 0x300u);
  ASSERT_EQ(f.len, kFdCommandBytes);
  const Decoded d = decode_frame(f.id, true, std::span<const uint8_t>(f.data.data(), f.len), BusMode::kFd, ids);
  ASSERT_EQ(d.kind, FrameKind::kCommand) << d.reason;
  EXPECT_EQ(d.command.seq, 9);
  EXPECT_EQ(d.command.theta_target[23], -123);
}

TEST(WhiskerProtocol, CommandOnClassicIsOneFramePerBoardInBoardOrder) {
  MotorCommand c;
  c.enable_mask = 0xFFFFFF;
  for (int w = 0; w < kNumWhiskers; ++w) c.theta_target[w] = static_cast<int16_t>(w);
  const ProtocolIds ids;
  CommandFrames out;
  encode_command(c, BusMode::kClassic, ids, out);
  ASSERT_EQ(out.count, kNumBoards);
  for (int b = 0; b < kNumBoards; ++b) {
    const CommandFrame& f = out.frames[static_cast<std::size_t>(b)];
    EXPECT_FALSE(f.fd);
    EXPECT_EQ(f.id, command_board_id(ids, b));
    ASSERT_EQ(f.len, kClassicBytes);
    const Decoded d = decode_frame(f.id, false, std::span<const uint8_t>(f.data.data(), f.len), BusMode::kClassic, ids);
    ASSERT_EQ(d.kind, FrameKind::kCommand) << d.reason;
    EXPECT_EQ(d.command_board, b);
    EXPECT_EQ(d.command.theta_target[b * kWhiskersPerBoard + 3], b * kWhiskersPerBoard + 3);
  }
}

TEST(WhiskerProtocol, ClassicFragmentsAssembleIntoBoardSample) {
  SampleAssembler a(BusMode::kClassic);
  const BoardSample in = make_sample(2, 0);
  std::array<uint8_t, 8> buf{};
  int completed = 0;
  for (int k = 0; k < kWhiskersPerBoard; ++k) {
    WhiskerFragment f{2, 200, k, kBoardMotorDisabled, in.whiskers[k]};
    encode_fragment(f, buf);
    const Decoded d = decode_frame(0x183, false, buf, BusMode::kClassic);
    ASSERT_EQ(d.kind, FrameKind::kFragment) << d.reason;
    completed += a.add(d.fragment);
  }
  EXPECT_EQ(completed, 1);
  EXPECT_EQ(a.latest(2).seq, 200);
  EXPECT_EQ(a.latest(2).whiskers[3].theta, in.whiskers[3].theta);
  EXPECT_EQ(a.latest(2).status, kBoardMotorDisabled);
}

TEST(WhiskerProtocol, LostFragmentDropsTheSampleAndCountsTheGap) {
  SampleAssembler a(BusMode::kClassic);
  auto feed = [&](uint8_t seq, int skip) {
    for (int k = 0; k < kWhiskersPerBoard; ++k) {
      if (k != skip) a.add(WhiskerFragment{0, seq, k, 0, {}});
    }
  };
  feed(1, -1);
  feed(2, 1);  // incomplete
  feed(3, -1);
  EXPECT_EQ(a.samples(0), 2);
  EXPECT_EQ(a.incomplete(), 1);
  EXPECT_EQ(a.gaps(0), 1);
}

TEST(WhiskerProtocol, SequenceGapsAreCountedPerBoardAcrossWraparound) {
  SampleAssembler a(BusMode::kFd);
  for (uint16_t s : {65533, 65534, 1, 2}) a.add(make_sample(1, s));  // 65535 and 0 lost
  a.add(make_sample(4, 10));
  a.add(make_sample(4, 11));
  a.add(make_sample(4, 11));  // duplicate: not a gap, not new
  a.add(make_sample(1, 0));  // late: arrived after 1 and 2
  EXPECT_EQ(a.late(), 1);
  EXPECT_EQ(a.gaps(1), 2);
  EXPECT_EQ(a.gaps(4), 0);
  EXPECT_EQ(a.samples(4), 2);
  EXPECT_EQ(a.total_gaps(), 2);
}

TEST(WhiskerProtocol, RebootedBoardIsResynchronisedAfterAFewLateSamples) {
  SampleAssembler a(BusMode::kFd);
  for (uint16_t s = 1000; s < 1010; ++s) a.add(make_sample(2, s));
  a.add(make_sample(3, 7));
  // Board 2 reboots: its counter restarts at 0, every new seq looks like a late frame.
  int accepted = 0;
  for (uint16_t s = 0; s < SampleAssembler::kResyncAfterLate; ++s) accepted += a.add(make_sample(2, s));
  EXPECT_EQ(accepted, 1);  // the last of the run
  EXPECT_EQ(a.resyncs(), 1);
  EXPECT_EQ(a.late(), SampleAssembler::kResyncAfterLate - 1);
  EXPECT_EQ(a.latest(2).seq, SampleAssembler::kResyncAfterLate - 1);
  const int64_t gaps = a.gaps(2);
  EXPECT_EQ(gaps, 0);
  EXPECT_TRUE(a.add(make_sample(2, SampleAssembler::kResyncAfterLate)));
  EXPECT_EQ(a.gaps(2), gaps);  // streaming normally again, no gap
  EXPECT_EQ(a.latest(3).seq, 7);  // other boards untouched
}

TEST(WhiskerProtocol, ABootUpHeartbeatRestartsTheBoardsSequenceWithoutAGap) {
  // Board 2 at seq 40000 reboots and restarts at 0: a step of 25536, in the lower half of the u16
  // space, so without its boot-up it counts as 25535 lost samples.
  SampleAssembler without(BusMode::kFd), with(BusMode::kFd);
  for (SampleAssembler* a : {&without, &with}) {
    for (uint16_t s = 39990; s <= 40000; ++s) a->add(make_sample(2, s));
    a->add(make_sample(3, 7));
  }
  EXPECT_TRUE(without.add(make_sample(2, 0)));
  EXPECT_EQ(without.gaps(2), 25535) << "the phantom gap the boot-up heartbeat prevents";
  std::array<uint8_t, 2> buf{};
  encode_heartbeat({2, kNmtBootUp, 0}, buf);
  const Decoded hb = decode_frame(0x703, false, buf, BusMode::kFd);
  ASSERT_EQ(hb.kind, FrameKind::kHeartbeat);
  ASSERT_EQ(hb.heartbeat.state, kNmtBootUp);
  with.restart(hb.heartbeat.board);
  EXPECT_TRUE(with.has_sample(2)) << "the last sample before the reboot is still the latest";
  EXPECT_TRUE(with.add(make_sample(2, 0)));
  EXPECT_TRUE(with.add(make_sample(2, 2)));
  EXPECT_EQ(with.gaps(2), 1) << "no gap to the restart; seq 1 lost after it";
  EXPECT_EQ(with.resyncs(), 1);
  EXPECT_EQ(with.late(), 0);
  EXPECT_EQ(with.latest(3).seq, 7);
  // A board's first boot-up (nothing received from it before) is not a restart.
  SampleAssembler fresh(BusMode::kClassic);
  fresh.restart(5);
  EXPECT_EQ(fresh.resyncs(), 0);
}

TEST(WhiskerProtocol, SingleLateFramesNeverResynchronise) {
  SampleAssembler a(BusMode::kClassic);
  auto sample = [&](uint8_t seq) {
    bool done = false;
    for (int k = 0; k < kWhiskersPerBoard; ++k) done = a.add(WhiskerFragment{4, seq, k, 0, {}});
    return done;
  };
  // Every other sample is followed by a reordered old one: late each time, but never consecutive.
  for (int s = 100; s < 140; s += 2) {
    EXPECT_TRUE(sample(static_cast<uint8_t>(s)));
    EXPECT_FALSE(sample(static_cast<uint8_t>(s - 5)));
  }
  EXPECT_EQ(a.late(), 20);
  EXPECT_EQ(a.resyncs(), 0);
  EXPECT_EQ(a.latest(4).seq, 138);
}

TEST(WhiskerProtocol, CalibrationAppliesOffsetGainAndRotation) {
  WhiskerCalibration c;
  c.offset_x = 100;
  c.offset_y = -100;
  c.gain_x = 0.001;
  c.gain_y = 0.002;
  c.rotation = M_PI / 2;
  c.theta_offset = 10;
  const CalibratedWhisker out = calibrate({1100, -100, 10 + 512, false}, c);
  // (1.0, 0) rotated by 90 deg -> (0, 1)
  EXPECT_NEAR(out.x, 0.0, 1e-6);
  EXPECT_NEAR(out.y, 1.0, 1e-6);
  EXPECT_NEAR(out.theta, M_PI / 4, 1e-6);
  EXPECT_EQ(theta_to_counts(M_PI / 4, c), 10 + 512);
  EXPECT_EQ(theta_to_counts(10.0, c), kThetaLimit);  // clamped
}

TEST(WhiskerProtocol, UncalibrateInvertsCalibrationWithinOneCount) {
  WhiskerCalibration c;
  c.offset_x = 37;
  c.offset_y = -12;
  c.gain_x = 0.0007;
  c.gain_y = -0.0011;
  c.rotation = 0.7;
  c.theta_offset = 25;
  c.theta_gain = 0.0016;
  const double cr = std::cos(c.rotation), sr = std::sin(c.rotation);
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(-0.9, 0.9);
  for (int i = 0; i < 500; ++i) {
    const double theta = u(rng), x = u(rng), y = u(rng);
    const WhiskerRaw raw = uncalibrate(theta, x, y, c);
    const CalibratedWhisker back = calibrate(raw, c);
    // Half a count of rounding per axis, seen through the gain and the rotation.
    const double step_x = 0.5 * (std::abs(cr * c.gain_x) + std::abs(sr * c.gain_y)) + 1e-6;
    const double step_y = 0.5 * (std::abs(sr * c.gain_x) + std::abs(cr * c.gain_y)) + 1e-6;
    EXPECT_NEAR(back.x, x, step_x);
    EXPECT_NEAR(back.y, y, step_y);
    EXPECT_NEAR(back.theta, theta, 0.5 * c.theta_gain + 1e-6);
  }
}

TEST(WhiskerProtocol, UncalibrateSaturatesHallCountsAndClampsTheta) {
  const WhiskerCalibration c;  // defaults: full scale 1 = 2047 counts
  const WhiskerRaw big = uncalibrate(3.0, 1.5, -4.0, c);
  EXPECT_EQ(big.x, kHallLimit);
  EXPECT_EQ(big.y, -kHallLimit);
  EXPECT_EQ(big.theta, kThetaLimit);
  const WhiskerRaw exact = uncalibrate(-M_PI / 4, 0.5, 0.25, c);
  EXPECT_EQ(exact.x, 1024);  // 0.5 * 2047 = 1023.5 rounds away from zero
  EXPECT_EQ(exact.y, 512);   // 511.75
  EXPECT_EQ(exact.theta, -512);
  // The saturated counts decode as valid (|value| == 2047 is saturation, not out of range).
  BoardSample s;
  s.whiskers[0] = big;
  std::array<uint8_t, kFdSampleBytes> buf{};
  ASSERT_EQ(encode_sample_fd(s, buf), kFdSampleBytes);
  EXPECT_EQ(decode_frame(sample_id({}, 0), true, buf, BusMode::kFd).kind, FrameKind::kSample);
}

TEST(WhiskerProtocol, BusLoadMatchesTheDocumentedTable) {
  // docs/can-protocol.md: FD 1/5 Mbit/s at 500 Hz, and classic 1 Mbit/s at 100 Hz, fit; classic at
  // 500 Hz does not.
  const BusLoad fd = bus_load(BusMode::kFd, 500, 1e6, 5e6);
  EXPECT_NEAR(fd.frames_per_s, 3560, 1e-9);
  EXPECT_GT(fd.busy_fraction, 0.30);
  EXPECT_LT(fd.busy_fraction, 0.45);
  EXPECT_LT(bus_load(BusMode::kClassic, 100, 1e6, 1e6).busy_fraction, 0.45);
  EXPECT_GT(bus_load(BusMode::kClassic, 500, 1e6, 1e6).busy_fraction, 1.0);
  // Classic 8-byte frame, worst-case stuffing: 135 bits.
  EXPECT_NEAR(frame_time_us(BusMode::kClassic, 8, 1e6, 1e6), 135.0, 1e-9);
}

TEST(WhiskerProtocol, RandomBytesNeverCrashAndAreCounted) {
  std::mt19937 rng(42);
  DecodeCounters counters;
  std::array<uint8_t, 64> buf{};
  for (int i = 0; i < 20000; ++i) {
    const uint32_t id = rng() % 0x800;
    const std::size_t len = rng() % 65;
    for (auto& b : buf) b = static_cast<uint8_t>(rng());
    const Decoded d = decode_frame(id, rng() % 2, std::span(buf.data(), len), i % 3 ? BusMode::kFd : BusMode::kClassic);
    counters.count(d);
    if (d.kind == FrameKind::kRejected) {
      EXPECT_STRNE(d.reason, "");
    }
  }
  EXPECT_EQ(counters.frames, 20000);
  EXPECT_GT(counters.rejected[static_cast<int>(Reject::kUnknownId)], 0);
  EXPECT_GT(counters.total_rejected(), 19000);
}
