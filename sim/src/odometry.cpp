// Simulated odometry (see odometry.h).
#include "whiskeye/sim/odometry.h"

namespace whiskeye::sim {

OdometryModel::OdometryModel(const OdometryNoise& noise, const Pose2& start, uint64_t seed)
    : noise_(noise), pose_(start), rng_(seed) {}

OdometrySample OdometryModel::step(double vx, double vy, double omega, double dt) {
  OdometrySample s;
  s.vx = noise_.scale_v * vx + noise_.bias_vx + noise_.sigma_v * normal_(rng_);
  s.vy = noise_.scale_v * vy + noise_.bias_vy + noise_.sigma_v * normal_(rng_);
  s.omega = omega + noise_.bias_omega + noise_.sigma_omega * normal_(rng_);
  if (dt > 0.0) pose_ = integrate_body_velocity(pose_, s.vx, s.vy, s.omega, dt);
  s.pose = pose_;
  return s;
}

}  // namespace whiskeye::sim
