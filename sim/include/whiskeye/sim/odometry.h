// Simulated base odometry: the true body-frame velocity corrupted by a scale error, a constant bias
// and white noise (seeded), integrated into a dead-reckoned pose exactly as a base would (arc
// integration of each sample's velocity over the sample period). Pure.
#pragma once

#include "whiskeye/common/se2.h"
#include "whiskeye/sim/world.h"

#include <cstdint>
#include <random>

namespace whiskeye::sim {

struct OdometrySample {
  Pose2 pose;          // dead-reckoned, odometry frame
  double vx = 0.0;     // measured body-frame velocity, m/s
  double vy = 0.0;
  double omega = 0.0;  // rad/s
};

class OdometryModel {
 public:
  OdometryModel(const OdometryNoise& noise, const Pose2& start, uint64_t seed);

  // One sample: measures the true velocity (held over the last dt seconds) and integrates it.
  // The first call (dt = 0) only measures.
  OdometrySample step(double vx, double vy, double omega, double dt);

 private:
  OdometryNoise noise_;
  Pose2 pose_;
  std::mt19937_64 rng_;
  std::normal_distribution<double> normal_{0.0, 1.0};
};

}  // namespace whiskeye::sim
