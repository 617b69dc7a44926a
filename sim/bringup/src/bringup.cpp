// Simulated bring-up sessions and a drawn true calibration (see bringup.h).
#include "whiskeye/sim/bringup.h"

#include <algorithm>
#include <cmath>
#include <random>
#include <utility>

namespace whiskeye::sim {

TrueCalibration draw_true_calibration(uint64_t seed) {
  std::mt19937_64 rng(seed);
  auto uniform = [&](double lo, double hi) { return std::uniform_real_distribution<double>(lo, hi)(rng); };
  TrueCalibration t;
  const wp::WhiskerCalibration nominal;
  for (wp::WhiskerCalibration& c : t.calibration) {
    c.offset_x = std::round(uniform(-150.0, 150.0) * 10.0) / 10.0;
    c.offset_y = std::round(uniform(-150.0, 150.0) * 10.0) / 10.0;
    c.gain_x = nominal.gain_x * uniform(0.8, 1.25);
    c.gain_y = nominal.gain_y * uniform(0.8, 1.25);
    c.rotation = uniform(-0.35, 0.35);
    c.theta_offset = std::round(uniform(-80.0, 80.0) * 10.0) / 10.0;
    c.theta_gain = nominal.theta_gain * uniform(0.9, 1.1);
  }
  t.mirrored_board = std::uniform_int_distribution<int>(0, wp::kNumBoards - 1)(rng);
  for (int k = 0; k < wp::kWhiskersPerBoard; ++k) {
    wp::WhiskerCalibration& c = t.calibration[static_cast<std::size_t>(t.mirrored_board * wp::kWhiskersPerBoard + k)];
    c.gain_y = -c.gain_y;
  }
  for (int w = 0; w < wp::kNumWhiskers; ++w) t.channel[static_cast<std::size_t>(w)] = w;
  std::uniform_int_distribution<int> whisker(0, wp::kNumWhiskers - 1);
  t.swapped[0] = whisker(rng);
  do {
    t.swapped[1] = whisker(rng);
  } while (t.swapped[1] == t.swapped[0]);
  std::swap(t.channel[static_cast<std::size_t>(t.swapped[0])], t.channel[static_cast<std::size_t>(t.swapped[1])]);
  return t;
}

bool parse_session(const std::string& name, Session& session) {
  const std::pair<const char*, Session> names[] = {
      {"rest", Session::kRest}, {"taps", Session::kTaps}, {"sweep", Session::kSweep}, {"jig", Session::kJig}};
  for (const auto& [n, s] : names) {
    if (name == n) {
      session = s;
      return true;
    }
  }
  return false;
}

namespace {

// One whisker pushed along one of its axes: ramp up, hold, ramp down, then quiet.
struct Push {
  int whisker = 0;
  int axis = 0;  // 0: x, 1: y
  double t0 = 0, ramp = 0.1, hold = 0.3, amplitude = 0;
  double at(double t) const {
    const double u = t - t0;
    if (u <= 0 || u >= 2 * ramp + hold) return 0.0;
    if (u < ramp) return amplitude * u / ramp;
    if (u < ramp + hold) return amplitude;
    return amplitude * (2 * ramp + hold - u) / ramp;
  }
};

constexpr double kQuiet = 0.5;  // s between pushes and before the first

// The sweep: from 0 up past the upper stop, down past the lower one, back to 0; the encoder stays at
// a stop while the drive pushes beyond it.
double sweep_theta(double t, const SessionParams& p, double& duration) {
  const double over = p.theta_stop + 10.0 * kPi / 180.0;  // commanded beyond the stops
  const double leg = over / p.sweep_rate;
  duration = kQuiet + 4 * leg + kQuiet;
  double u = t - kQuiet;
  double cmd = 0.0;
  if (u > 0 && u < leg) {
    cmd = p.sweep_rate * u;
  } else if (u >= leg && u < 3 * leg) {
    cmd = over - p.sweep_rate * (u - leg);
  } else if (u >= 3 * leg && u < 4 * leg) {
    cmd = -over + p.sweep_rate * (u - 3 * leg);
  }
  return std::clamp(cmd, -p.theta_stop, p.theta_stop);
}

}  // namespace

int64_t run_session(const SessionParams& p, const SessionSink& sink) {
  std::mt19937_64 rng(p.seed);
  std::normal_distribution<double> noise(0.0, p.noise);
  std::vector<int> order = p.order;
  if (order.empty()) {
    for (int w = 0; w < wp::kNumWhiskers; ++w) order.push_back(w);
  }
  std::vector<Push> pushes;
  double duration = p.rest_s;
  if (p.session == Session::kTaps || p.session == Session::kJig) {
    const bool jig = p.session == Session::kJig;
    std::uniform_real_distribution<double> tap_size(0.6, 1.0);
    double t = kQuiet;
    for (int w : order) {
      for (int axis = 0; axis < 2; ++axis) {
        Push push{w, axis, t, 0.1, jig ? 1.0 : 0.3, jig ? p.jig_deflection : p.tap_deflection * tap_size(rng)};
        pushes.push_back(push);
        t += 2 * push.ramp + push.hold + kQuiet;
      }
    }
    duration = t;
  } else if (p.session == Session::kSweep) {
    sweep_theta(0.0, p, duration);
  }
  const auto period_us = static_cast<int64_t>(std::llround(1e6 / p.rate_hz));
  const auto n = static_cast<int64_t>(std::floor(duration * p.rate_hz));
  rcp::WhiskerSample s;
  WhiskerHealth health;
  std::size_t next_push = 0;
  for (int64_t i = 0; i < n; ++i) {
    const double t = static_cast<double>(i) / p.rate_hz;
    s.utime = p.start_utime + i * period_us;
    s.seq = i;
    double theta = 0.0;
    if (p.session == Session::kSweep) theta = sweep_theta(t, p, duration);
    for (int w = 0; w < wp::kNumWhiskers; ++w) {
      s.theta[w] = theta;
      const bool stuck = std::find(p.stuck.begin(), p.stuck.end(), w) != p.stuck.end();
      s.deflection_x[w] = stuck ? 0.0 : noise(rng);
      s.deflection_y[w] = stuck ? 0.0 : noise(rng);
      s.valid[w] = true;
      health.stale[w] = p.silent_board >= 0 && w / wp::kWhiskersPerBoard == p.silent_board;
      health.fault[w] = p.fault_at_s >= 0 && t >= p.fault_at_s && w / wp::kWhiskersPerBoard == 0;
    }
    while (next_push < pushes.size() && t > pushes[next_push].t0 + 2 * pushes[next_push].ramp + pushes[next_push].hold) {
      ++next_push;
    }
    if (next_push < pushes.size()) {
      const Push& push = pushes[next_push];
      (push.axis == 0 ? s.deflection_x : s.deflection_y)[push.whisker] += push.at(t);
    }
    sink(s, health);
  }
  return n;
}

}  // namespace whiskeye::sim
