// Synthetic inputs for the core's tests: seeded random images and whisk cycles generated with the
// same contact law the simulator's plant uses (|deflection| = bend_gain·(θ − θ_c)/r after contact).
#pragma once

#include "whiskeye/common/robot_geometry.h"
#include "whiskeye/slam/types.h"

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

namespace whiskeye::slam::test {

// A grey image with smooth random blobs (so block-averaging keeps structure).
inline std::vector<uint8_t> random_image(int w, int h, uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::vector<double> v(static_cast<size_t>(w * h), 0.3);
  for (int b = 0; b < 12; ++b) {
    const double cx = u(rng) * w, cy = u(rng) * h, rad = 20 + u(rng) * 60, amp = u(rng) - 0.4;
    for (int y = 0; y < h; ++y) {
      for (int x = 0; x < w; ++x) {
        const double d2 = (x - cx) * (x - cx) + (y - cy) * (y - cy);
        v[static_cast<size_t>(y * w + x)] += amp * std::exp(-d2 / (2 * rad * rad));
      }
    }
  }
  std::vector<uint8_t> out(v.size());
  for (size_t i = 0; i < v.size(); ++i) out[i] = static_cast<uint8_t>(std::lround(std::clamp(v[i], 0.0, 1.0) * 255));
  return out;
}

struct SyntheticContact {
  int whisker;
  double theta_contact;  // rad
  double radius;         // m
};

// One 1 s whisk cycle at 500 Hz: θ sweeps −0.5 → 0.9 → −0.5 rad (cosine); whiskers in `contacts`
// deflect by the bend law in the direction `dir` (rad), plus Gaussian noise of sd `noise`.
// `speed_gain` adds the plant's whisking-speed term −speed_gain·θ̇ to x (0.004: the simulator's).
inline WhiskCycleInput whisk_cycle(const RobotGeometry& g, const std::vector<SyntheticContact>& contacts,
                                   double noise, uint32_t seed, int64_t utime0 = 0, int samples = 500,
                                   double speed_gain = 0.004) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> n(0.0, noise);
  WhiskCycleInput c;
  c.utime_start = utime0;
  c.utime_end = utime0 + 1000000;
  for (int i = 0; i < samples; ++i) {
    WhiskSample s;
    s.utime = utime0 + static_cast<int64_t>(i) * 1000000 / samples;
    const double ph = static_cast<double>(i) / samples;
    const double theta = -0.5 + 1.4 * (0.5 - 0.5 * std::cos(2 * kPi * ph));
    const double theta_dot = 1.4 * 0.5 * 2 * kPi * std::sin(2 * kPi * ph);  // per second (1 s cycle)
    for (int w = 0; w < kNumWhiskers; ++w) {
      s.theta[static_cast<size_t>(w)] = static_cast<float>(theta);
      double m = 0.0;
      for (const SyntheticContact& k : contacts) {
        if (k.whisker == w && theta > k.theta_contact) {
          m = g.whiskers[static_cast<size_t>(w)].bend_gain * (theta - k.theta_contact) / k.radius;
        }
      }
      s.deflection_x[static_cast<size_t>(w)] = static_cast<float>(0.8 * m - speed_gain * theta_dot + n(rng));
      s.deflection_y[static_cast<size_t>(w)] = static_cast<float>(0.6 * m + n(rng));
      s.contact[static_cast<size_t>(w)] = m > 0.04;
    }
    c.samples.push_back(s);
  }
  return c;
}

// Contacts of all whiskers of the given rows with θ_c and r varied by seed (a "place").
inline std::vector<SyntheticContact> random_contacts(uint32_t seed, int count = 12) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> th(-0.2, 0.5), fr(0.3, 0.9);
  std::vector<SyntheticContact> out;
  const RobotGeometry g = default_robot_geometry();
  for (int w = 0; w < count; ++w) {
    const int wid = (w * 7 + static_cast<int>(seed)) % kNumWhiskers;
    bool dup = false;
    for (const auto& c : out) dup = dup || c.whisker == wid;
    if (dup) continue;
    out.push_back({wid, th(rng), fr(rng) * g.whiskers[static_cast<size_t>(wid)].length});
  }
  return out;
}

}  // namespace whiskeye::slam::test
