// Whisker plant model (see plant.h).
#include <whiskeye/rcp/plant.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

namespace whiskeye::rcp {

PlantParams::PlantParams() {
  for (int w = 0; w < kNumWhiskers; ++w) whisker_length[w] = kWhiskEyeRowLength[row_of(w)];
}

void load(const ParamNode& node, PlantParams& p) {
  const auto fail = [&](const std::string& key, const std::string& what) {
    throw ParamError(node.source() + ": '" + node.path_of(key) + "' " + what);
  };
  if (node.has("whisker_length_by_row") && node.has("whisker_length")) {
    fail("whisker_length", "and 'whisker_length_by_row' are exclusive");
  }
  std::vector<double> by_row(kWhiskEyeRowLength.begin(), kWhiskEyeRowLength.end());
  if (node.has("whisker_length_by_row")) {
    node.get("whisker_length_by_row", by_row);
    if (by_row.size() != static_cast<std::size_t>(kWhiskerRows)) fail("whisker_length_by_row", "must list 4 lengths (m)");
    for (int w = 0; w < kNumWhiskers; ++w) p.whisker_length[w] = by_row[row_of(w)];
  }
  if (node.has("whisker_length")) {
    std::vector<double> all(p.whisker_length.begin(), p.whisker_length.end());
    node.get("whisker_length", all);
    if (all.size() != static_cast<std::size_t>(kNumWhiskers)) fail("whisker_length", "must list 24 lengths (m)");
    std::copy(all.begin(), all.end(), p.whisker_length.begin());
  }
  for (double l : p.whisker_length) {
    if (!(l > 0.0 && l < 1.0)) fail(node.has("whisker_length") ? "whisker_length" : "whisker_length_by_row", "lengths must be in (0, 1) m");
  }
  node.get("natural_frequency_hz", p.natural_frequency_hz, 0.5, 200.0);
  node.get("damping_ratio", p.damping_ratio, 0.05, 5.0);
  node.get("substeps", p.substeps, 1, 100);
  double limit_deg = rad_to_deg(p.theta_limit);
  node.get("theta_limit_deg", limit_deg, 1.0, 90.0);
  p.theta_limit = deg_to_rad(limit_deg);
  double initial_deg = rad_to_deg(p.initial_theta);
  node.get("initial_theta_deg", initial_deg, -90.0, 90.0);
  p.initial_theta = deg_to_rad(initial_deg);
  node.get("deflection_gain", p.deflection_gain, 0.0, 100.0);
  node.get("contact_load", p.contact_load, 0.0, 1e6);
  node.get("speed_gain", p.speed_gain, 0.0, 1.0);
  node.get("noise_sigma", p.noise_sigma, 0.0, 1.0);
  node.get("theta_noise_sigma", p.theta_noise_sigma, 0.0, 1.0);
  node.get("saturation", p.saturation, 0.01, 100.0);
}

WhiskerPlant::WhiskerPlant(const PlantParams& params, uint64_t seed) : params_(params), rng_(seed) {
  for (auto& s : state_) s.theta = params_.initial_theta;
}

void WhiskerPlant::set_obstacle(int whisker, std::optional<Obstacle> obstacle) {
  obstacles_.at(static_cast<std::size_t>(whisker)) = obstacle;
  update_contact(whisker);
}

void WhiskerPlant::update_contact(int w) {
  WhiskerTrueState& s = state_[w];
  const std::optional<Obstacle>& o = obstacles_[w];
  const double length = params_.whisker_length[w];
  s.in_contact = o && o->radial_distance > 0.0 && o->radial_distance <= length && s.theta > o->contact_angle;
  double dx = 0.0;
  double dy = 0.0;
  if (s.in_contact) {
    s.bending = s.theta - o->contact_angle;
    // Cantilever with a point contact at r: base moment ~ 3 EI bending / r.
    s.contact_deflection = params_.deflection_gain * o->stiffness_scale * s.bending * length / o->radial_distance;
    dx = s.contact_deflection * std::cos(o->deflection_direction);
    dy = s.contact_deflection * std::sin(o->deflection_direction);
  } else {
    s.bending = 0.0;
    s.contact_deflection = 0.0;
  }
  s.deflection_x = dx - params_.speed_gain * s.theta_dot;
  s.deflection_y = dy;
}

WhiskerSample WhiskerPlant::step(int64_t utime, const PerWhisker<double>& theta_command) {
  const double dt = started_ ? static_cast<double>(utime - last_utime_) * 1e-6 : 0.0;
  started_ = true;
  last_utime_ = utime;
  const double wn = kTwoPi * params_.natural_frequency_hz;
  const double kp = wn * wn;
  const double kd = 2.0 * params_.damping_ratio * wn;
  const int n = params_.substeps;
  const double h = dt > 0.0 ? dt / n : 0.0;

  WhiskerSample out;
  out.utime = utime;
  out.seq = ++seq_;
  for (int w = 0; w < kNumWhiskers; ++w) {
    WhiskerTrueState& s = state_[w];
    const double cmd = std::clamp(theta_command[w], -params_.theta_limit, params_.theta_limit);
    for (int k = 0; h > 0.0 && k < n; ++k) {
      // Semi-implicit Euler of the PD-controlled joint, loaded by the whisker's base moment.
      const double acc = kp * (cmd - s.theta) - kd * s.theta_dot - params_.contact_load * s.contact_deflection;
      s.theta_dot += acc * h;
      s.theta += s.theta_dot * h;
      if (std::abs(s.theta) > params_.theta_limit) {
        s.theta = std::clamp(s.theta, -params_.theta_limit, params_.theta_limit);
        s.theta_dot = 0.0;
      }
      update_contact(w);
    }
    if (h == 0.0) update_contact(w);
    const double sat = params_.saturation;
    out.theta[w] = s.theta + params_.theta_noise_sigma * normal_(rng_);
    out.deflection_x[w] = std::clamp(s.deflection_x + params_.noise_sigma * normal_(rng_), -sat, sat);
    out.deflection_y[w] = std::clamp(s.deflection_y + params_.noise_sigma * normal_(rng_), -sat, sat);
    out.valid[w] = true;
  }
  return out;
}

}  // namespace whiskeye::rcp
