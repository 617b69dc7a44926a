// Odometry beyond these is a corrupt sample, not motion (a Robotino drives at most ~1 m/s): based
// refuses such a reply from the base, slamd (its edge and the SLAM core) such an ODOMETRY sample.
#pragma once

namespace whiskeye {

inline constexpr double kMaxOdometrySpeed = 20.0;     // m/s
inline constexpr double kMaxOdometryTurnRate = 50.0;  // rad/s

}  // namespace whiskeye
