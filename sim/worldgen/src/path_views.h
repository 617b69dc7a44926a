// What the aliasing check and the drafting of a world share (private to whiskeye_worldgen): polar
// angles along the circular path, and the noise-free views rendered along it as slamd's templates.
#pragma once

#include "whiskeye/sim/alias_check.h"

#include <cmath>
#include <cstdint>
#include <vector>

namespace whiskeye::sim::worldgen {

// Tactile landmarks stand at most this far along the path from their centre (for spacing them).
inline constexpr double kObjectHalfLength = 0.15;
// How far from the head the generator takes the whiskers to reach: its own figure, not read from
// the robot geometry (robot.yaml's longest whisker is 0.1717 m, its farthest tip 0.2155 m from the
// head's origin); either of those would redraw every generated world.
inline constexpr double kReach = 0.20;

// Polar angle (deg) that `m` metres of the head's path span.
inline double m_to_deg(double m, double head_r) { return m / head_r * 180.0 / kPi; }

// Half a whisk cycle's travel along the path, in degrees: how far a place's touch reaches.
inline double half_cycle_deg(const rcp::PatternParams& whisking, double speed, double head_r) {
  return 0.5 * (1.0 / whisking.frequency_hz) * speed / head_r * 180.0 / kPi;
}

// A pair of views looks alike within this matcher distance (margin × slamd's visual match limit).
inline double alike_limit(const AliasCheckParams& p) { return p.margin * p.match.threshold_visual * p.match.sigma_visual; }

inline double circular_deg(double a) {
  a = std::fmod(a, 360.0);
  return a < 0.0 ? a + 360.0 : a;
}

inline double circular_gap_deg(double a, double b) {
  const double d = std::abs(circular_deg(a - b));
  return std::min(d, 360.0 - d);
}

// Pose of the base at polar angle `deg` of the world's circle (facing as the trajectory does).
Pose2 pose_at_angle(const Trajectory& trajectory, double deg);

struct Views {
  std::vector<double> angles_deg;
  int w = 0, h = 0;
  std::vector<std::vector<uint8_t>> column_major;  // one template per angle, the matcher's layout

  // The view rendered nearest to polar angle `deg`.
  int index_of(double deg) const {
    const int n = static_cast<int>(angles_deg.size());
    return static_cast<int>(std::lround(circular_deg(deg) / (360.0 / n))) % n;
  }
};


// The noise-free views (no camera noise, no lighting change) every p.angle_step_deg of the path.
Views render_views(const World& world, const RobotGeometry& robot, const AliasCheckParams& p);

}  // namespace whiskeye::sim::worldgen
