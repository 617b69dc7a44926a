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

// ---- a whole log, as whiskeye-calibrate reads one

// What one line of a `candump -l` log is. Its trailing "\r" (a log that went through Windows) is no
// part of it.
enum class CandumpLine {
  kFrame,       // a data frame with a standard id, in `frame`
  kErrorFrame,  // an error frame; its time in frame.utime
  kOther,       // an extended-id or a remote (RTR) frame: none is the whisker bus's; skipped, as
                // listening on the bus skips them
  kBlank,
  kInvalid,     // not a line of the format (a time beyond int64 microseconds included)
};
CandumpLine classify_candump_line(std::string_view line, LoggedFrame& frame, std::string& interface);

// candump writes at most ~180 bytes a line (a 64-byte FD frame on a 15-character interface): a
// longer line is no candump log, and a reader never holds more than this of one (/dev/zero, a
// sparse file and binary garbage are one endless line).
inline constexpr std::size_t kMaxCandumpLineBytes = 512;

// Splits a log read in pieces of any size into its lines (without "\n"), numbered from 1, holding
// at most kMaxCandumpLineBytes of the one not finished. Pure: bytes in, lines out.
class CandumpLines {
 public:
  // Hands each line `bytes` completes to on_line(number, line). False, with too_long() the number of
  // the line, as soon as a line is longer than kMaxCandumpLineBytes (nothing more is taken then).
  template <typename F>
  bool feed(std::string_view bytes, F&& on_line) {
    while (!bytes.empty()) {
      const std::size_t end = bytes.find('\n');
      const std::string_view piece = bytes.substr(0, end);
      if (line_.size() + piece.size() > kMaxCandumpLineBytes) {
        too_long_ = number_ + 1;
        return false;
      }
      line_.append(piece);
      if (end == std::string_view::npos) return true;
      on_line(++number_, std::string_view(line_));
      line_.clear();
      bytes.remove_prefix(end + 1);
    }
    return true;
  }
  // The last line when the log does not end in "\n".
  template <typename F>
  void finish(F&& on_line) {
    if (!line_.empty()) on_line(++number_, std::string_view(line_));
    line_.clear();
  }
  int64_t too_long() const { return too_long_; }

 private:
  std::string line_;
  int64_t number_ = 0, too_long_ = 0;
};

}  // namespace whiskeye::can
