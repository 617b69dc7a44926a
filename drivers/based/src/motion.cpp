// Speed/acceleration limits and the deadman between BASE_CMD and the base.
#include "whiskeye/based/motion.h"

#include <algorithm>
#include <cmath>

namespace whiskeye::based {

Velocity clamp_speed(const Velocity& v, const CommandParams& p) {
  Velocity out = v;
  const double speed = std::hypot(v.vx, v.vy);
  if (speed > p.max_linear_speed) {
    const double k = speed > 0.0 ? p.max_linear_speed / speed : 0.0;
    out.vx *= k;
    out.vy *= k;
  }
  out.omega = std::clamp(v.omega, -p.max_angular_speed, p.max_angular_speed);
  return out;
}

Velocity limit_accel(const Velocity& from, const Velocity& to, double dt, const CommandParams& p) {
  Velocity out = to;
  const double dvx = to.vx - from.vx;
  const double dvy = to.vy - from.vy;
  const double dv = std::hypot(dvx, dvy);
  const double max_dv = p.max_linear_accel * dt;
  if (dv > max_dv) {
    const double k = max_dv / dv;
    out.vx = from.vx + k * dvx;
    out.vy = from.vy + k * dvy;
  }
  const double max_dw = p.max_angular_accel * dt;
  out.omega = from.omega + std::clamp(to.omega - from.omega, -max_dw, max_dw);
  return out;
}

bool MotionGate::command(const Velocity& target, int64_t now_us) {
  if (!std::isfinite(target.vx) || !std::isfinite(target.vy) || !std::isfinite(target.omega)) {
    return false;
  }
  target_ = clamp_speed(target, params_);
  last_command_us_ = now_us;
  have_command_ = true;
  return true;
}

Velocity MotionGate::step(int64_t now_us) {
  // Bound dt: a late first step or a stalled caller must not license a big velocity change.
  const double dt = have_step_ ? std::clamp(static_cast<double>(now_us - last_step_us_) * 1e-6, 0.0,
                                            2.0 / params_.rate_hz)
                               : 1.0 / params_.rate_hz;
  have_step_ = true;
  last_step_us_ = now_us;
  const bool expired = !have_command_ || static_cast<double>(now_us - last_command_us_) * 1e-6 > params_.deadman_s;
  if (expired) {
    if (!deadman_ && !(output_ == Velocity{})) ++trips_;
    deadman_ = true;
    output_ = Velocity{};
    return output_;
  }
  deadman_ = false;
  output_ = limit_accel(output_, target_, dt, params_);
  return output_;
}

}  // namespace whiskeye::based
