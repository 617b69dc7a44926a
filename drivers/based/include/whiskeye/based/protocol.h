// The Robotino REST protocol as pure functions: base URL, the odometry reply, the omnidrive command.
//   GET  /data/odometry  → [x, y, rot, vx, vy, omega, seq]   (m, rad, m/s, rad/s; seq counts samples)
//   POST /data/omnidrive ← [vx, vy, omega]                    (body frame; the base stops by itself
//                                                               when no command comes for 200 ms)
// No I/O here: the daemon's HTTP client hands bodies in and takes bodies out.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>

namespace whiskeye::based {

// The base stops by itself when no omnidrive command has reached it for this long.
inline constexpr int64_t kBaseStopsAfterUs = 200'000;

// The largest reply body based accepts (seven numbers take under 200 bytes).
inline constexpr std::size_t kMaxReplyBytes = 4096;

inline constexpr const char* kOdometryPath = "/data/odometry";
inline constexpr const char* kOmnidrivePath = "/data/omnidrive";

struct BaseUrl {
  std::string host;
  int port = 80;
};

// Parses "http://host[:port][/]". False with a reason for anything else (https, a path, bad port).
bool parse_base_url(std::string_view url, BaseUrl& out, std::string& error);

// One odometry sample as the base reports it (pose in the base's odometry frame, body velocity).
struct OdometrySample {
  int64_t utime = 0;    // sample time on the wall clock (odometry_t.utime), set by the caller (see sample_utime)
  int64_t mono_us = 0;  // the same instant on the monotonic clock: every timing check uses this one,
                        // so an NTP step of the wall clock neither fakes nor hides a jump
  int64_t seq = 0;
  double x = 0.0;
  double y = 0.0;
  double theta = 0.0;
  double vx = 0.0;
  double vy = 0.0;
  double omega = 0.0;
};

// Parses the body of GET /data/odometry: exactly seven finite numbers, seq integral. On failure
// returns false and says what was wrong (not JSON, not an array, wrong length, element k not a
// finite number, seq not an integer). `out.utime` is left untouched.
bool parse_odometry_reply(std::string_view body, OdometrySample& out, std::string& error);

// The JSON body of POST /data/omnidrive.
std::string format_omnidrive_command(double vx, double vy, double omega);

// The base samples its odometry somewhere between our request and its reply; with no better
// knowledge the middle of the round trip is the unbiased estimate.
inline int64_t sample_utime(int64_t reply_received_utime, int64_t round_trip_us) {
  return reply_received_utime - round_trip_us / 2;
}

}  // namespace whiskeye::based
