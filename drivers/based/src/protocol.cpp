// Robotino REST bodies and URL, parsed and formatted with nlohmann-json; no I/O.
#include "whiskeye/common/odometry_limits.h"
#include "whiskeye/based/protocol.h"

#include <nlohmann/json.hpp>

#include <charconv>
#include <cmath>
#include <limits>

namespace whiskeye::based {

bool parse_base_url(std::string_view url, BaseUrl& out, std::string& error) {
  constexpr std::string_view kScheme = "http://";
  if (url.substr(0, kScheme.size()) != kScheme) {
    error = "the base URL must start with http:// (got \"" + std::string(url) + "\")";
    return false;
  }
  std::string_view rest = url.substr(kScheme.size());
  if (!rest.empty() && rest.back() == '/') rest.remove_suffix(1);
  if (rest.find('/') != std::string_view::npos) {
    error = "the base URL must be http://host[:port] without a path (got \"" + std::string(url) + "\")";
    return false;
  }
  BaseUrl parsed;
  const std::size_t colon = rest.rfind(':');
  std::string_view host = rest;
  if (colon != std::string_view::npos) {
    host = rest.substr(0, colon);
    const std::string_view port = rest.substr(colon + 1);
    int value = 0;
    const auto [end, ec] = std::from_chars(port.data(), port.data() + port.size(), value);
    if (port.empty() || ec != std::errc() || end != port.data() + port.size() || value < 1 ||
        value > 65535) {
      error = "bad port \"" + std::string(port) + "\" in the base URL \"" + std::string(url) + "\"";
      return false;
    }
    parsed.port = value;
  }
  if (host.empty()) {
    error = "no host in the base URL \"" + std::string(url) + "\"";
    return false;
  }
  parsed.host = std::string(host);
  out = parsed;
  return true;
}

namespace {

// Bounds of a plausible reply (a Robotino drives at under 1 m/s): beyond them the tracker's
// re-anchoring would overflow or lose precision and every later sample would be wrong. Speeds: the
// limits of odometry_limits.h, which slamd applies too.
constexpr double kMaxPosition = 1e5;              // m
constexpr double kMaxHeading = 1e6;               // rad, in case the firmware does not wrap it

// A short description of an element for an error line: a scalar as it is, a string cut to 40
// characters, a container by its size (dump() recurses once per level: a deeply nested reply
// overflowed the stack).
std::string describe(const nlohmann::json& v) {
  if (v.is_array() || v.is_object()) return std::string("a JSON ") + v.type_name() + " of " + std::to_string(v.size()) + " elements";
  if (v.is_string()) {
    const auto& s = v.get_ref<const std::string&>();
    return nlohmann::json(s.substr(0, 40)).dump() + (s.size() > 40 ? "..." : "");
  }
  return v.dump();
}

}  // namespace

bool parse_odometry_reply(std::string_view body, OdometrySample& out, std::string& error) {
  if (body.size() > kMaxReplyBytes) {
    error = "odometry reply of " + std::to_string(body.size()) + " bytes, more than 4 KiB";
    return false;
  }
  // No exceptions: a malformed reply is routine input here, not an exceptional event.
  const nlohmann::json j = nlohmann::json::parse(body.begin(), body.end(), nullptr, false);
  const auto excerpt = [&] {
    std::string s(body.substr(0, 40));
    for (char& c : s) {
      if (c < 0x20 || c > 0x7e) c = '?';
    }
    return "\"" + s + (body.size() > 40 ? "...\"" : "\"");
  };
  if (j.is_discarded()) {
    error = "odometry reply is not JSON: " + excerpt();
    return false;
  }
  if (!j.is_array()) {
    error = "odometry reply is not a JSON array: " + excerpt();
    return false;
  }
  if (j.size() != 7) {
    error = "odometry reply has " + std::to_string(j.size()) + " elements, expected 7 [x, y, rot, vx, vy, omega, seq]";
    return false;
  }
  static const char* const kNames[7] = {"x", "y", "rot", "vx", "vy", "omega", "seq"};
  double v[7];
  for (std::size_t i = 0; i < 7; ++i) {
    if (!j[i].is_number()) {
      error = std::string("odometry reply element ") + kNames[i] + " is not a number: " + describe(j[i]);
      return false;
    }
    v[i] = j[i].get<double>();
    if (!std::isfinite(v[i])) {
      error = std::string("odometry reply element ") + kNames[i] + " is not finite";
      return false;
    }
  }
  static const double kLimits[6] = {kMaxPosition, kMaxPosition, kMaxHeading, kMaxOdometrySpeed, kMaxOdometrySpeed,
                                    kMaxOdometryTurnRate};
  for (std::size_t i = 0; i < 6; ++i) {
    if (std::abs(v[i]) > kLimits[i]) {
      error = std::string("odometry reply element ") + kNames[i] + " = " + nlohmann::json(v[i]).dump() +
              " is beyond any base's (" + nlohmann::json(kLimits[i]).dump() + ")";
      return false;
    }
  }
  int64_t seq = 0;
  if (j[6].is_number_integer()) {
    seq = j[6].is_number_unsigned() && j[6].get<uint64_t>() > uint64_t(std::numeric_limits<int64_t>::max())
              ? -1
              : j[6].get<int64_t>();
    if (seq < 0) {
      error = "odometry reply seq is negative or too large: " + describe(j[6]);
      return false;
    }
  } else if (v[6] == std::floor(v[6]) && v[6] >= 0.0 && v[6] < 9.0e18) {
    seq = static_cast<int64_t>(v[6]);  // some firmware may print it as 12.0
  } else {
    error = "odometry reply seq is not a non-negative integer: " + describe(j[6]);
    return false;
  }
  out.x = v[0];
  out.y = v[1];
  out.theta = v[2];
  out.vx = v[3];
  out.vy = v[4];
  out.omega = v[5];
  out.seq = seq;
  return true;
}

std::string format_omnidrive_command(double vx, double vy, double omega) {
  return nlohmann::json::array({vx, vy, omega}).dump();
}

}  // namespace whiskeye::based
