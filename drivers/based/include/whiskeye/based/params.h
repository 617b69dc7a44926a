// Parameters of the `based` daemon (Festo Robotino base over its REST API), one struct with working
// defaults, loaded strictly from YAML (config/based.yaml documents every key).
#pragma once

#include "whiskeye/common/params.h"

#include <string>

namespace whiskeye::based {

struct OdometryParams {
  double poll_rate_hz = 50.0;         // GET /data/odometry rate
  double reply_timeout_s = 0.1;       // a reply later than this counts as dropped
  double connect_timeout_s = 0.5;
  // A reset of the base's odometry is a position change that the reported velocity cannot explain:
  // |Δp| > jump_velocity_factor · max(|v_prev|, |v_now|) · Δt + jump_margin_m (likewise for θ).
  double jump_velocity_factor = 2.0;
  double jump_margin_m = 0.05;
  double jump_margin_rad = 0.1;
  // After a reset, keep ODOMETRY continuous (re-anchor on the velocity-predicted pose) instead of
  // passing the base's new origin through.
  bool continuous_after_reset = true;
  double stale_after_s = 0.5;  // no new seq for this long → DEGRADED
};

struct CommandParams {
  double rate_hz = 20.0;  // POST /data/omnidrive rate; the base stops by itself after 200 ms
  double reply_timeout_s = 0.1;
  double deadman_s = 0.5;  // no BASE_CMD for this long → zero velocity
  double max_linear_speed = 0.5;   // m/s, norm of (vx, vy)
  double max_angular_speed = 1.5;  // rad/s
  double max_linear_accel = 0.5;   // m/s², norm of the change of (vx, vy)
  double max_angular_accel = 2.0;  // rad/s²
};

struct ConnectionParams {
  double backoff_initial_s = 0.1;  // wait after a failed connect, doubled per failure
  double backoff_max_s = 2.0;
  double fault_after_s = 2.0;      // no valid new odometry for this long → FAULT
  double degraded_hold_s = 2.0;    // a fault keeps the state DEGRADED for this long
  double log_quiet_s = 5.0;        // a fault burst ends after this long without that fault
};

struct BasedParams {
  std::string url = "http://192.168.0.1:80";
  OdometryParams odometry;
  CommandParams command;
  ConnectionParams connection;
};

// Throws ParamError naming `where` (a key, or an option) when `url` is not http://host[:port].
void check_url(const std::string& url, const std::string& where);
// Loads every key (absent keys keep their defaults); throws ParamError naming a bad or unknown key.
void load(const ParamNode& node, BasedParams& p);

}  // namespace whiskeye::based
