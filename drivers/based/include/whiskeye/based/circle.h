// The paper's experiment on the real robot: revolve around a centre on a circle of radius R while
// facing outwards. For an omnidirectional base facing away from the centre, moving along the circle
// is pure sideways motion: vx = 0, vy = V, omega = V / R (V > 0 turns counter-clockwise around the
// centre, V < 0 clockwise). The speed follows a trapezoid (ramp up, cruise, ramp down to stop after
// N laps); vy and omega are ramped together so the path stays on the circle during the ramps.
// Pure: velocity as a function of time since the start; open loop (laps counted from the commanded
// speed, not from odometry).
#pragma once

#include "whiskeye/based/motion.h"
#include "whiskeye/based/params.h"

#include <string>

namespace whiskeye::based {

struct CircleSpec {
  double radius = 1.0;  // m
  double speed = 0.1;   // m/s tangential, signed
  int laps = 0;         // 0 = until stopped
};

class CircleTrajectory {
 public:
  // Throws std::invalid_argument naming the problem: radius or speed not positive/finite, or a speed
  // beyond the command limits (clipping would leave the circle).
  CircleTrajectory(const CircleSpec& spec, const CommandParams& limits);

  Velocity command(double t) const;  // t: seconds since the start
  bool finished(double t) const;
  double duration() const;  // infinity when laps = 0
  double accel() const { return accel_; }  // tangential m/s² used for the ramps
  std::string describe() const;

 private:
  double speed_along(double t) const;  // |tangential speed| at t

  CircleSpec spec_;
  double accel_ = 0.0;
  double peak_ = 0.0;     // |V| actually reached (lower on a triangular profile)
  double t_ramp_ = 0.0;   // duration of each ramp
  double t_cruise_ = 0.0;
  double t_total_ = 0.0;
};

}  // namespace whiskeye::based
