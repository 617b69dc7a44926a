// The WhiskEye's geometry, shared by everything that must agree on it: the simulator (which makes
// contacts happen), slamd's tactile template (which estimates contact points from θ and deflection),
// and whiskerd (whisker numbering). Loaded from config/robot.yaml; defaults are the standard layout.
//
// Frames (all right-handed, SI units):
//   base: the Robotino's centre on the floor, x forward, y left, z up. Odometry and GROUND_TRUTH are
//         poses of this frame.
//   head: origin at the whisker array's centre, x forward (the camera's optical axis), y left, z up.
//         T_base_head is fixed (the neck is not moved in these experiments).
// Whisker w = row * 6 + column: rows 0..3 top to bottom; columns 0..2 on the left side and 3..5 on
// the right side, each side front to back. Board b carries whiskers 4b..4b+3 (docs/can-protocol.md).
// Protraction angle θ (rad, + = protraction) rotates a whisker about the head's z axis through its
// base, sweeping it forward: azimuth(θ) = azimuth0 − side·θ, side = +1 left, −1 right.
#pragma once

#include "whiskeye/common/params.h"
#include "whiskeye/common/se2.h"
#include "whiskeye/common/whisker_array.h"

#include <array>

namespace whiskeye {

struct Vec3 {
  double x = 0.0;
  double y = 0.0;
  double z = 0.0;
  bool operator==(const Vec3&) const = default;
};

struct WhiskerGeometry {
  int row = 0;
  int column = 0;
  double side = 1.0;           // +1 left, -1 right
  Vec3 p_base_in_head;         // m
  double azimuth0 = 0.0;       // rad, direction at θ = 0, ccw from head x
  double elevation = 0.0;      // rad, up positive
  double length = 0.1;         // m
  double base_diameter = 1.0e-3;  // m (taper: the whisker is a cone from base to tip)
  double tip_diameter = 0.2e-3;   // m
  // Calibrated base deflection per rad of bending, for a point contact at radial distance r:
  //   deflection ≈ bend_gain · (θ − θ_contact) / r      (cantilever: moment ∝ bending / r)
  // so r ≈ bend_gain · Δθ / Δdeflection. Units: deflection · m / rad.
  double bend_gain = 0.02;

  bool operator==(const WhiskerGeometry&) const = default;
};

struct CameraGeometry {
  int width = 640;
  int height = 480;
  double hfov = 1.57;          // rad
  double fps = 5.0;
  Vec3 p_camera_in_head{0.02, 0.0, 0.03};  // m; the camera looks along head x
  bool operator==(const CameraGeometry&) const = default;
};

struct RobotGeometry {
  Pose2 T_base_head{0.25, 0.0, 0.0};  // head pose in the base frame (planar part)
  double head_height = 0.30;          // m, head origin above the floor
  CameraGeometry camera;
  std::array<WhiskerGeometry, kNumWhiskers> whiskers;
  bool operator==(const RobotGeometry&) const = default;

  // Unit direction of whisker w at protraction θ, head frame.
  Vec3 whisker_direction(int w, double theta) const;
  // Point at radial distance r along whisker w at protraction θ, head frame.
  Vec3 whisker_point(int w, double theta, double r) const;
};

// The standard WhiskEye layout (no file needed).
RobotGeometry default_robot_geometry();

// Radius (m) of the circle the head travels on while the base circles at `base_radius` facing
// outwards (the head is mounted ahead of the base: T_base_head).
double head_path_radius(double base_radius, const RobotGeometry& robot);

// Loads `robot:` parameters (see config/robot.yaml): layout parameters from which every whisker is
// generated, plus optional per-whisker overrides. Strict: unknown keys are errors.
void load(const ParamNode& node, RobotGeometry& geometry);

}  // namespace whiskeye
