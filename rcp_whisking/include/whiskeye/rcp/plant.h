// Plant model of the WhiskEye whisker array, for the controller's tests, rcp-plant and vita-sim:
// per whisker a PD-controlled protraction joint, an optional obstacle met at a given protraction
// angle and radial distance, a base deflection that grows with bending after contact (cantilever:
// base moment ~ bending angle / r, so a contact nearer the base bends the base more), and Hall x/y
// output with noise plus a whisking-speed-dependent term. Deterministic for a given seed.
#pragma once

#include <whiskeye/common/params.h>
#include <whiskeye/common/se2.h>
#include <whiskeye/rcp/types.h>

#include <array>
#include <cstdint>
#include <optional>
#include <random>

namespace whiskeye::rcp {

// WhiskEye whisker lengths by position on a board (= row), m.
constexpr std::array<double, kWhiskerRows> kWhiskEyeRowLength{0.0604, 0.0810, 0.1115, 0.1717};

struct PlantParams {
  PerWhisker<double> whisker_length{};  // m; default from kWhiskEyeRowLength by row
  double natural_frequency_hz = 20.0;   // closed-loop PD joint bandwidth
  double damping_ratio = 0.8;
  int substeps = 8;                     // integration steps per control period
  double theta_limit = 60.0 * kPi / 180.0;   // joint range +-, rad
  double initial_theta = -30.0 * kPi / 180.0;
  // Calibrated deflection per rad of bending for a contact at the whisker tip; a contact at radial
  // distance r gives gain * bending * length / r (moment ~ 3 EI bending / r).
  double deflection_gain = 0.6;
  // Joint deceleration per unit of deflection (the whisker's moment loads the motor), rad/s^2.
  double contact_load = 2000.0;
  // Whisking-speed term: drag/inertia bends the whisker against its motion, per rad/s, along x.
  double speed_gain = 0.004;
  double noise_sigma = 0.005;        // Hall x and y noise, calibrated units (1 sigma)
  double theta_noise_sigma = 0.0005; // encoder noise, rad
  double saturation = 1.0;           // |x|, |y| clip (ADC full scale)

  PlantParams();
};

// Loads section keys (whisker_length_by_row or whisker_length list, natural_frequency_hz, ...).
// Does not call check_no_unknown_keys() (the caller does).
void load(const ParamNode& node, PlantParams& params);

struct Obstacle {
  double contact_angle = 0.0;    // protraction angle theta at which the whisker first touches, rad
  double radial_distance = 0.05; // m from the whisker base along the whisker (> length: out of reach)
  double stiffness_scale = 1.0;  // scales the deflection (a soft surface < 1)
  double deflection_direction = kPi;  // direction of the base deflection in the x/y plane (pi: -x, pushed back)
};

struct WhiskerTrueState {
  double theta = 0.0;      // true protraction angle, rad
  double theta_dot = 0.0;  // rad/s
  bool in_contact = false;
  double bending = 0.0;             // theta - contact_angle while in contact, rad
  double contact_deflection = 0.0;  // |xy| due to the contact alone
  double deflection_x = 0.0;        // true x (contact + speed term), before noise and clipping
  double deflection_y = 0.0;
};

class WhiskerPlant {
 public:
  WhiskerPlant(const PlantParams& params, uint64_t seed);

  // No obstacle (nullopt) or one obstacle per whisker.
  void set_obstacle(int whisker, std::optional<Obstacle> obstacle);
  const std::optional<Obstacle>& obstacle(int whisker) const { return obstacles_[whisker]; }

  // Advances from the previous call's time to `utime` tracking `theta_command` (held over the
  // interval), then samples. The first call only samples. seq increases by one per call.
  WhiskerSample step(int64_t utime, const PerWhisker<double>& theta_command);

  const PerWhisker<WhiskerTrueState>& true_state() const { return state_; }
  const PlantParams& params() const { return params_; }

 private:
  void update_contact(int w);

  PlantParams params_;
  std::mt19937_64 rng_;
  std::normal_distribution<double> normal_{0.0, 1.0};
  PerWhisker<std::optional<Obstacle>> obstacles_{};
  PerWhisker<WhiskerTrueState> state_{};
  bool started_ = false;
  int64_t last_utime_ = 0;
  int64_t seq_ = 0;
};

}  // namespace whiskeye::rcp
