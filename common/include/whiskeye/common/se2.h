// Planar rigid-body math used everywhere: angle wrapping, SE(2) compose / inverse / between,
// interpolation on the circle. One place, so every module agrees on the conventions:
//   - angles in rad, wrapped to (-pi, pi];
//   - Pose2 T_a_b is frame b expressed in frame a; compose(T_a_b, T_b_c) = T_a_c;
//   - between(T_w_a, T_w_b) = T_a_b = inverse(T_w_a) ∘ T_w_b (the metrics' x_a ⊖ x_b reads "b in a").
#pragma once

#include <cmath>
#include <numbers>

namespace whiskeye {

constexpr double kPi = std::numbers::pi;
constexpr double kTwoPi = 2.0 * std::numbers::pi;

// Wraps an angle to (-pi, pi].
inline double wrap_angle(double a) {
  if (a > -kPi && a <= kPi) return a;
  a = std::fmod(a + kPi, kTwoPi);
  if (a <= 0.0) a += kTwoPi;
  return a - kPi;
}

// Wraps an angle to [0, 2pi).
inline double wrap_angle_positive(double a) {
  a = std::fmod(a, kTwoPi);
  if (a < 0.0) a += kTwoPi;
  return a >= kTwoPi ? 0.0 : a;
}

// The signed smallest rotation from b to a, in (-pi, pi].
inline double angle_diff(double a, double b) { return wrap_angle(a - b); }

inline double deg_to_rad(double deg) { return deg * kPi / 180.0; }
inline double rad_to_deg(double rad) { return rad * 180.0 / kPi; }

struct Pose2 {
  double x = 0.0;
  double y = 0.0;
  double theta = 0.0;

  bool operator==(const Pose2&) const = default;
};

// T_a_c = T_a_b ∘ T_b_c
inline Pose2 compose(const Pose2& a_b, const Pose2& b_c) {
  const double c = std::cos(a_b.theta);
  const double s = std::sin(a_b.theta);
  return {a_b.x + c * b_c.x - s * b_c.y, a_b.y + s * b_c.x + c * b_c.y,
          wrap_angle(a_b.theta + b_c.theta)};
}

// T_b_a from T_a_b
inline Pose2 inverse(const Pose2& a_b) {
  const double c = std::cos(a_b.theta);
  const double s = std::sin(a_b.theta);
  return {-c * a_b.x - s * a_b.y, s * a_b.x - c * a_b.y, wrap_angle(-a_b.theta)};
}

// T_a_b from T_w_a and T_w_b
inline Pose2 between(const Pose2& w_a, const Pose2& w_b) { return compose(inverse(w_a), w_b); }

// Applies T_a_b to a point given in frame b, giving it in frame a.
inline void transform_point(const Pose2& a_b, double bx, double by, double& ax, double& ay) {
  const double c = std::cos(a_b.theta);
  const double s = std::sin(a_b.theta);
  ax = a_b.x + c * bx - s * by;
  ay = a_b.y + s * bx + c * by;
}

// Linear interpolation of position and shortest-arc interpolation of heading, t in [0, 1].
inline Pose2 interpolate(const Pose2& p0, const Pose2& p1, double t) {
  return {p0.x + t * (p1.x - p0.x), p0.y + t * (p1.y - p0.y),
          wrap_angle(p0.theta + t * angle_diff(p1.theta, p0.theta))};
}

// Integrates a body-frame velocity (vx forward, vy left, omega ccw) over dt from `pose`, exactly for
// constant velocities (the arc, not a straight-line Euler step).
inline Pose2 integrate_body_velocity(const Pose2& pose, double vx, double vy, double omega, double dt) {
  const double dth = omega * dt;
  double dx_body;
  double dy_body;
  if (std::abs(dth) < 1e-9) {
    dx_body = vx * dt;
    dy_body = vy * dt;
  } else {
    // ∫0^dt R(ω t) v dt, expressed in the body frame at the start.
    const double s = std::sin(dth) / omega;
    const double c = (1.0 - std::cos(dth)) / omega;
    dx_body = s * vx - c * vy;
    dy_body = c * vx + s * vy;
  }
  return compose(pose, Pose2{dx_body, dy_body, dth});
}

}  // namespace whiskeye
