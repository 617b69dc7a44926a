// The `candump -l` lines whiskeye-calibrate reads besides data frames (whiskeye/can/candump.h): error
// frames, which the bus check counts and fails on.

#include <gtest/gtest.h>

#include <vector>

#include "whiskeye/calibrate/estimators.h"
#include "whiskeye/can/candump.h"

using namespace whiskeye;

TEST(CandumpLog, AnErrorFrameLineIsRecognisedWithItsTime) {
  int64_t utime = 0;
  EXPECT_TRUE(can::parse_candump_error_line("(1700000001.250000) can0 20000004#0004000000000000", utime));
  EXPECT_EQ(utime, 1700000001250000);
}

TEST(CandumpLog, DataFramesAndGarbageAreNotErrorFrames) {
  int64_t utime = 0;
  EXPECT_FALSE(can::parse_candump_error_line("(1700000001.250000) can0 701#05", utime));
  EXPECT_FALSE(can::parse_candump_error_line("(1700000001.250000) can0 00000701#05", utime));  // extended, no error flag
  EXPECT_FALSE(can::parse_candump_error_line("(1700000001.25) can0 20000004#00", utime));       // not 6 decimals
  EXPECT_FALSE(can::parse_candump_error_line("hello", utime));
  can::LoggedFrame f;
  std::string interface;
  EXPECT_FALSE(can::parse_candump_line("(1700000001.250000) can0 20000004#0004000000000000", f, interface));
}

namespace {

struct Frame {
  int64_t utime;
  uint32_t id;
  bool fd;
  std::vector<uint8_t> data;
};

// One second of every board's FD samples at 500 Hz and heartbeats at 10 Hz, from `start_utime`.
std::vector<Frame> one_second_of_every_board(int64_t start_utime) {
  std::vector<Frame> frames;
  std::vector<uint8_t> sample(wp::kFdSampleBytes), beat(wp::kHeartbeatBytes);
  for (int i = 0; i < 500; ++i) {
    for (int b = 0; b < wp::kNumBoards; ++b) {
      wp::BoardSample s;
      s.board = b;
      s.seq = static_cast<uint16_t>(i);
      wp::encode_sample_fd(s, sample);
      frames.push_back({start_utime + i * 2000, wp::sample_id({}, b), true, sample});
      if (i % 50 == 0) {
        wp::encode_heartbeat({b, 0x05, 0}, beat);
        frames.push_back({start_utime + i * 2000, wp::heartbeat_id({}, b), false, beat});
      }
    }
  }
  return frames;
}

calibrate::Recording recording_of(const std::vector<Frame>& frames) {
  calibrate::Recording r(wp::BusMode::kFd, wp::ProtocolIds{});
  for (const Frame& f : frames) r.add_frame(f.utime, f.id, f.fd, f.data);
  return r;
}

}  // namespace

TEST(CalibrateBus, AnErrorFrameOnTheBusFailsTheCheck) {
  // One second of every board's samples and heartbeats, then one error frame.
  calibrate::Recording r = recording_of(one_second_of_every_board(0));
  EXPECT_TRUE(calibrate::check_bus(r, 500.0, 1.0).ok) << calibrate::format_bus_report(calibrate::check_bus(r, 500.0, 1.0));
  r.add_error_frame(999000);
  const calibrate::BusReport rep = calibrate::check_bus(r, 500.0, 1.0);
  EXPECT_FALSE(rep.ok);
  EXPECT_EQ(rep.error_frames, 1);
}

// The lines of a log besides standard data frames: live listening skips extended-id and remote
// frames, and so does reading a log of them (one made the whole log "not a candump -l line").
TEST(CandumpLog, ExtendedIdAndRemoteFramesAreOtherLinesAndCrlfIsNoPartOfALine) {
  can::LoggedFrame f;
  std::string interface;
  using can::CandumpLine;
  EXPECT_EQ(can::classify_candump_line("(1700000001.250000) can0 181##1000102\r", f, interface), CandumpLine::kFrame);
  EXPECT_EQ(f.id, 0x181u);
  EXPECT_EQ(f.data, (std::vector<uint8_t>{0x00, 0x01, 0x02}));
  EXPECT_EQ(can::classify_candump_line("(1700000001.250000) can0 701#05\r", f, interface), CandumpLine::kFrame);
  EXPECT_EQ(interface, "can0");
  EXPECT_EQ(can::classify_candump_line("(1700000001.250000) can0 12345678#0011", f, interface), CandumpLine::kOther);
  EXPECT_EQ(can::classify_candump_line("(1700000001.250000) can0 12345678##1001122", f, interface), CandumpLine::kOther);
  EXPECT_EQ(can::classify_candump_line("(1700000001.250000) can0 701#R", f, interface), CandumpLine::kOther);
  EXPECT_EQ(can::classify_candump_line("(1700000001.250000) can0 701#R8\r", f, interface), CandumpLine::kOther);
  EXPECT_EQ(can::classify_candump_line("(1700000001.250000) can0 12345678#R", f, interface), CandumpLine::kOther);
  EXPECT_EQ(can::classify_candump_line("(1700000001.250000) can0 20000004#0004000000000000\r", f, interface),
            CandumpLine::kErrorFrame);
  EXPECT_EQ(f.utime, 1700000001250000);
  EXPECT_EQ(can::classify_candump_line("\r", f, interface), CandumpLine::kBlank);
  EXPECT_EQ(can::classify_candump_line("", f, interface), CandumpLine::kBlank);
  for (const char* bad : {"(1700000001.250000) can0 701#R88", "(1700000001.250000) can0 701#RX",
                          "(1700000001.250000) can0 1234567#00", "(1700000001.250000) can0 12345678#001",
                          "(1700000001.250000) can0 123456789#00", "(1700000001.250000) can0 701#05\r\r", "hello\r"}) {
    EXPECT_EQ(can::classify_candump_line(bad, f, interface), CandumpLine::kInvalid) << bad;
  }
}

// 18 digits of seconds overflowed int64 microseconds silently (a time before 1970 came out).
TEST(CandumpLog, ATimeBeyondInt64MicrosecondsIsNoCandumpLine) {
  can::LoggedFrame f;
  std::string interface;
  EXPECT_FALSE(can::parse_candump_line("(999999999999999999.000000) can0 701#05", f, interface));
  EXPECT_FALSE(can::parse_candump_line("(9223372036855.000000) can0 701#05", f, interface));
  int64_t utime = 0;
  EXPECT_FALSE(can::parse_candump_error_line("(9223372036855.000000) can0 20000004#00", utime));
  ASSERT_TRUE(can::parse_candump_line("(9223372036853.000000) can0 701#05", f, interface));
  EXPECT_EQ(f.utime, 9223372036853000000);
  EXPECT_EQ(can::classify_candump_line("(9223372036855.000000) can0 701#05", f, interface), can::CandumpLine::kInvalid);
}

// A log is split into lines whatever pieces it is read in, and no line longer than candump writes is
// held: /dev/zero or a sparse file is one endless line.
TEST(CandumpLog, LinesAreSplitAcrossPiecesAndAnOverlongLineStopsTheSplit) {
  can::CandumpLines lines;
  std::vector<std::pair<int64_t, std::string>> got;
  const auto take = [&](int64_t n, std::string_view line) { got.emplace_back(n, std::string(line)); };
  EXPECT_TRUE(lines.feed("ab\ncd", take));
  EXPECT_TRUE(lines.feed("e\n\nf", take));
  lines.finish(take);
  EXPECT_EQ(got, (std::vector<std::pair<int64_t, std::string>>{{1, "ab"}, {2, "cde"}, {3, ""}, {4, "f"}}));
  can::CandumpLines endless;
  got.clear();
  const std::string zeros(300, '\0');
  EXPECT_TRUE(endless.feed("ok\n", take));
  EXPECT_TRUE(endless.feed(zeros, take));
  EXPECT_FALSE(endless.feed(zeros, take));  // 600 bytes of line 2
  EXPECT_EQ(endless.too_long(), 2);
  EXPECT_EQ(got.size(), 1u);
  can::CandumpLines exact;
  EXPECT_TRUE(exact.feed(std::string(can::kMaxCandumpLineBytes, 'x') + "\n", take));
}

// The rates are of the time the log spans frame to frame: reversed, two sessions one after the other
// or one frame 30 years late, "last line minus first" gave 0.0 Hz for every board.
TEST(CalibrateBus, TheSpanIsTheTimeBetweenFramesWhateverTheirOrder) {
  const std::vector<Frame> second = one_second_of_every_board(1'700'000'000'000'000);
  const auto span_of = [](const std::vector<Frame>& frames) { return recording_of(frames).span_us(); };
  EXPECT_EQ(span_of(second), 998000);
  std::vector<Frame> reversed(second.rbegin(), second.rend());
  EXPECT_EQ(span_of(reversed), 998000);
  std::vector<Frame> wild = second;
  wild[wild.size() / 2].utime += int64_t{30} * 365 * 86400 * 1000000;
  // The steps to and from it count for nothing: at most one sample period is lost.
  EXPECT_GE(span_of(wild), 998000 - 2000);
  EXPECT_LE(span_of(wild), 998000);
  std::vector<Frame> sessions = second;
  for (Frame f : second) {
    f.utime -= int64_t{86400} * 1000000;  // the day before, logged after
    sessions.push_back(f);
  }
  EXPECT_EQ(span_of(sessions), 2 * 998000);
  std::vector<Frame> extremes = {{INT64_MAX, 0x701, false, {5}}, {0, 0x701, false, {5}}, {INT64_MAX, 0x701, false, {5}}};
  EXPECT_EQ(span_of(extremes), 0);
}
