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

TEST(CalibrateBus, AnErrorFrameOnTheBusFailsTheCheck) {
  calibrate::Recording r(wp::BusMode::kFd, wp::ProtocolIds{});
  // One second of every board's samples and heartbeats, then one error frame.
  std::vector<uint8_t> sample(wp::kFdSampleBytes), beat(wp::kHeartbeatBytes);
  for (int i = 0; i < 500; ++i) {
    for (int b = 0; b < wp::kNumBoards; ++b) {
      wp::BoardSample s;
      s.board = b;
      s.seq = static_cast<uint16_t>(i);
      wp::encode_sample_fd(s, sample);
      r.add_frame(i * 2000, wp::sample_id({}, b), true, sample);
      if (i % 50 == 0) {
        wp::encode_heartbeat({b, 0x05, 0}, beat);
        r.add_frame(i * 2000, wp::heartbeat_id({}, b), false, beat);
      }
    }
  }
  EXPECT_TRUE(calibrate::check_bus(r, 500.0, 1.0).ok) << calibrate::format_bus_report(calibrate::check_bus(r, 500.0, 1.0));
  r.add_error_frame(999000);
  const calibrate::BusReport rep = calibrate::check_bus(r, 500.0, 1.0);
  EXPECT_FALSE(rep.ok);
  EXPECT_EQ(rep.error_frames, 1);
}
