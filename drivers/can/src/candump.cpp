// The `candump -l` text format (see candump.h).
#include "whiskeye/can/candump.h"

#include <cstdint>
#include <cstdio>

namespace whiskeye::can {

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

std::string format_candump_line(const LoggedFrame& f, std::string_view interface) {
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

namespace {

// "(<sec>.<usec>) <interface> ": the time and what follows the interface's name.
bool parse_stamp(std::string_view line, int64_t& utime, std::string_view& interface, std::string_view& rest) {
  if (line.size() < 4 || line.front() != '(') return false;
  const std::size_t close = line.find(") ");
  const std::size_t dot = line.find('.');
  if (close == std::string_view::npos || dot == std::string_view::npos || dot > close) return false;
  int64_t sec = 0, usec = 0;
  const std::string_view frac = line.substr(dot + 1, close - dot - 1);
  if (!parse_decimal(line.substr(1, dot - 1), sec) || frac.size() != 6 || !parse_decimal(frac, usec)) return false;
  if (sec > (INT64_MAX - 999999) / 1000000) return false;  // beyond int64 microseconds (year 292,277)
  utime = sec * 1000000 + usec;
  rest = line.substr(close + 2);
  const std::size_t space = rest.find(' ');
  if (space == 0 || space == std::string_view::npos) return false;
  interface = rest.substr(0, space);
  rest = rest.substr(space + 1);
  return true;
}

}  // namespace

bool parse_candump_line(std::string_view line, LoggedFrame& f, std::string& interface) {
  std::string_view name, rest;
  if (!parse_stamp(line, f.utime, name, rest)) return false;
  interface.assign(name);
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

bool parse_candump_error_line(std::string_view line, int64_t& utime) {
  std::string_view name, rest;
  if (!parse_stamp(line, utime, name, rest) || rest.size() < 9 || rest[8] != '#') return false;
  uint32_t id = 0;
  for (std::size_t i = 0; i < 8; ++i) {
    const int v = hex_value(rest[i]);
    if (v < 0) return false;
    id = id << 4 | static_cast<uint32_t>(v);
  }
  return (id & kCanErrFlag) != 0;
}

namespace {

bool all_hex(std::string_view s) {
  for (char c : s) {
    if (hex_value(c) < 0) return false;
  }
  return true;
}

// An extended-id frame (8 hex digits, the error flag clear: data, FD or remote) or a standard remote
// frame ("123#R", "123#R8": the optional length candump writes).
bool other_frame_line(std::string_view line) {
  int64_t utime = 0;
  std::string_view name, rest;
  if (!parse_stamp(line, utime, name, rest)) return false;
  const std::size_t hash = rest.find('#');
  if ((hash != 3 && hash != 8) || !all_hex(rest.substr(0, hash))) return false;
  std::string_view body = rest.substr(hash + 1);
  if (!body.empty() && body.front() == 'R') return body.size() == 1 || (body.size() == 2 && hex_value(body[1]) >= 0);
  if (hash == 3) return false;  // a standard data frame is parse_candump_line()'s
  uint32_t id = 0;
  for (char c : rest.substr(0, hash)) id = id << 4 | static_cast<uint32_t>(hex_value(c));
  if ((id & kCanErrFlag) != 0 || id > 0x1fffffff) return false;
  if (!body.empty() && body.front() == '#') {
    if (body.size() < 2 || hex_value(body[1]) < 0) return false;
    body.remove_prefix(2);
  }
  return body.size() % 2 == 0 && body.size() <= 128 && all_hex(body);
}

}  // namespace

CandumpLine classify_candump_line(std::string_view line, LoggedFrame& frame, std::string& interface) {
  if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
  if (line.empty()) return CandumpLine::kBlank;
  if (parse_candump_line(line, frame, interface)) return CandumpLine::kFrame;
  if (parse_candump_error_line(line, frame.utime)) return CandumpLine::kErrorFrame;
  if (other_frame_line(line)) return CandumpLine::kOther;
  return CandumpLine::kInvalid;
}

}  // namespace whiskeye::can
