// Loads BasedParams from YAML, strictly (see config/based.yaml for every key).
#include "whiskeye/based/params.h"

#include "whiskeye/based/protocol.h"

namespace whiskeye::based {

void check_url(const std::string& url, const std::string& where) {
  BaseUrl parsed;
  std::string error;
  if (!parse_base_url(url, parsed, error)) throw ParamError(where + ": " + error);
}

void load(const ParamNode& node, BasedParams& p) {
  node.get("url", p.url);
  check_url(p.url, node.path_of("url"));

  const ParamNode o = node.section("odometry");
  o.get("poll_rate_hz", p.odometry.poll_rate_hz, 0.5, 1000.0);
  o.get("reply_timeout_s", p.odometry.reply_timeout_s, 0.001, 10.0);
  o.get("connect_timeout_s", p.odometry.connect_timeout_s, 0.001, 10.0);
  o.get("jump_velocity_factor", p.odometry.jump_velocity_factor, 1.0, 100.0);
  o.get("jump_margin_m", p.odometry.jump_margin_m, 0.0, 100.0);
  o.get("jump_margin_rad", p.odometry.jump_margin_rad, 0.0, 3.2);
  o.get("continuous_after_reset", p.odometry.continuous_after_reset);
  o.get("stale_after_s", p.odometry.stale_after_s, 0.01, 60.0);

  const ParamNode c = node.section("command");
  // At least 10 Hz: the base stops by itself when commands are 200 ms apart.
  c.get("rate_hz", p.command.rate_hz, 10.0, 1000.0);
  c.get("reply_timeout_s", p.command.reply_timeout_s, 0.001, 10.0);
  c.get("deadman_s", p.command.deadman_s, 0.01, 10.0);
  c.get("max_linear_speed", p.command.max_linear_speed, 0.0, 3.0);
  c.get("max_angular_speed", p.command.max_angular_speed, 0.0, 10.0);
  c.get("max_linear_accel", p.command.max_linear_accel, 0.01, 20.0);
  c.get("max_angular_accel", p.command.max_angular_accel, 0.01, 50.0);

  const ParamNode n = node.section("connection");
  n.get("backoff_initial_s", p.connection.backoff_initial_s, 0.001, 10.0);
  n.get("backoff_max_s", p.connection.backoff_max_s, 0.001, 60.0);
  n.get("fault_after_s", p.connection.fault_after_s, 0.01, 600.0);
  n.get("degraded_hold_s", p.connection.degraded_hold_s, 0.0, 600.0);
  n.get("log_quiet_s", p.connection.log_quiet_s, 0.0, 3600.0);
  if (p.connection.backoff_max_s < p.connection.backoff_initial_s) {
    throw ParamError(n.source() + ": " + n.path_of("backoff_max_s") + " must be >= " +
                     n.path_of("backoff_initial_s"));
  }
  node.check_no_unknown_keys();
}

}  // namespace whiskeye::based
