// The text format of can-utils' `candump -l` log (one frame a line: "(1700000000.002000) can0
// 181##1<hex>" for an FD frame, "(1700000000.002000) can0 701#0500" for a classic one), written by
// vita-sim for `canplayer` and read by whiskeye-calibrate. Pure: strings in, frames out.
#pragma once

#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

namespace whiskeye::can {

// One CAN frame of a log: time, 11-bit id, FD or classic, FD flags (bit 0 BRS, bit 1 ESI) and data.
struct LoggedFrame {
  int64_t utime = 0;
  uint32_t id = 0;
  bool fd = false;
  uint8_t fd_flags = 0;
  std::vector<uint8_t> data;
};

// FD frames go out with bit-rate switching (the bus runs 1/5 Mbit/s, docs/can-protocol.md).
inline constexpr uint8_t kCanFdBrs = 0x01;
// The error-frame flag of a SocketCAN id (linux/can.h CAN_ERR_FLAG), as candump logs it.
inline constexpr uint32_t kCanErrFlag = 0x20000000;

// One line of `candump -l`, without the newline (ids as 3 hex digits, uppercase).
std::string format_candump_line(const LoggedFrame& frame, std::string_view interface);
// Parses one such line (the `candump -l` subset above: standard ids, data frames). False on any
// other text.
bool parse_candump_line(std::string_view line, LoggedFrame& frame, std::string& interface);
// An error frame's line ("(1700000000.002000) can0 20000004#0004000000000000"): true and its time.
bool parse_candump_error_line(std::string_view line, int64_t& utime);

}  // namespace whiskeye::can
