// What the base is told to do: the last BASE_CMD, limited in speed and acceleration, and forced to
// zero by a deadman when commands stop. Pure: the caller passes the time of each call.
#pragma once

#include "whiskeye/based/params.h"

#include <cstdint>

namespace whiskeye::based {

struct Velocity {  // body frame: vx forward, vy left (m/s), omega counter-clockwise (rad/s)
  double vx = 0.0;
  double vy = 0.0;
  double omega = 0.0;
  bool operator==(const Velocity&) const = default;
};

// Scales (vx, vy) to at most max_linear_speed (keeping the direction) and clamps |omega|.
Velocity clamp_speed(const Velocity& v, const CommandParams& p);
// Moves from `from` toward `to` by at most the acceleration limits over dt seconds; the linear
// part moves along the straight line in (vx, vy), so the direction of the change is kept.
Velocity limit_accel(const Velocity& from, const Velocity& to, double dt, const CommandParams& p);

class MotionGate {
 public:
  explicit MotionGate(const CommandParams& params) : params_(params) {}

  // A new target. False (and ignored, the deadman keeps running) if any component is not finite.
  bool command(const Velocity& target, int64_t now_us);

  // The velocity to send now. When the last command is older than deadman_s (or there never was
  // one) the output is zero at once, not ramped down: the deadman is a stop, like the base's own.
  Velocity step(int64_t now_us);

  // The base has stopped by itself (no command reached it for kBaseStopsAfterUs): the next output
  // ramps up from rest, not from what was last computed but never arrived.
  void base_stopped() { output_ = Velocity{}; }

  bool deadman_active() const { return deadman_; }
  // Number of times the deadman has stopped a moving command.
  int64_t deadman_trips() const { return trips_; }

 private:
  CommandParams params_;
  Velocity target_;
  Velocity output_;
  int64_t last_command_us_ = 0;
  int64_t last_step_us_ = 0;
  bool have_command_ = false;
  bool have_step_ = false;
  bool deadman_ = true;
  int64_t trips_ = 0;
};

}  // namespace whiskeye::based
