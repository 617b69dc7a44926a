// Velocity profile for driving around a circle while facing outwards (the paper's experiment).
#include "whiskeye/based/circle.h"

#include "whiskeye/common/se2.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>

namespace whiskeye::based {

CircleTrajectory::CircleTrajectory(const CircleSpec& spec, const CommandParams& limits) : spec_(spec) {
  if (!std::isfinite(spec.radius) || spec.radius <= 0.0) {
    throw std::invalid_argument("--circle RADIUS must be a positive number of metres");
  }
  if (!std::isfinite(spec.speed) || spec.speed == 0.0) {
    throw std::invalid_argument("--speed must be a non-zero number of m/s (its sign picks the direction)");
  }
  if (spec.laps < 0) throw std::invalid_argument("--laps must be >= 0 (0 = until stopped)");
  const double v = std::abs(spec.speed);
  if (v > limits.max_linear_speed) {
    std::ostringstream s;
    s << "--speed " << v << " m/s exceeds command.max_linear_speed " << limits.max_linear_speed;
    throw std::invalid_argument(s.str());
  }
  if (v / spec.radius > limits.max_angular_speed) {
    std::ostringstream s;
    s << "--speed " << v << " m/s on radius " << spec.radius << " m needs " << v / spec.radius
      << " rad/s, beyond command.max_angular_speed " << limits.max_angular_speed;
    throw std::invalid_argument(s.str());
  }
  // omega = V/R, so ramping V at a ramps omega at a/R: both limits must hold.
  accel_ = std::min(limits.max_linear_accel, limits.max_angular_accel * spec.radius);
  peak_ = v;
  t_ramp_ = v / accel_;
  if (spec.laps == 0) {
    t_cruise_ = std::numeric_limits<double>::infinity();
    t_total_ = std::numeric_limits<double>::infinity();
    return;
  }
  const double distance = kTwoPi * spec.radius * spec.laps;
  const double ramp_distance = v * v / (2.0 * accel_);
  if (2.0 * ramp_distance >= distance) {  // never reaches V: triangle
    peak_ = std::sqrt(accel_ * distance);
    t_ramp_ = peak_ / accel_;
    t_cruise_ = 0.0;
  } else {
    t_cruise_ = (distance - 2.0 * ramp_distance) / v;
  }
  t_total_ = 2.0 * t_ramp_ + t_cruise_;
}

double CircleTrajectory::speed_along(double t) const {
  if (t <= 0.0 || t >= t_total_) return 0.0;
  if (t < t_ramp_) return accel_ * t;
  if (t < t_ramp_ + t_cruise_) return peak_;
  return std::max(0.0, accel_ * (t_total_ - t));
}

Velocity CircleTrajectory::command(double t) const {
  const double v = std::copysign(speed_along(t), spec_.speed);
  return Velocity{0.0, v, v / spec_.radius};
}

bool CircleTrajectory::finished(double t) const { return t >= t_total_; }

double CircleTrajectory::duration() const { return t_total_; }

std::string CircleTrajectory::describe() const {
  std::ostringstream s;
  s.precision(4);
  s << "circle radius " << spec_.radius << " m, speed " << spec_.speed << " m/s (vy " << spec_.speed
    << " m/s, omega " << spec_.speed / spec_.radius << " rad/s, "
    << (spec_.speed > 0 ? "counter-clockwise" : "clockwise") << "), ramps at " << accel_ << " m/s², ";
  if (spec_.laps == 0) {
    s << "until stopped";
  } else {
    s << spec_.laps << " lap(s) in " << t_total_ << " s";
  }
  return s.str();
}

}  // namespace whiskeye::based
