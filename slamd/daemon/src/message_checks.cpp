// slamd's checks of decoded messages (message_checks.h).
#include "message_checks.h"

#include "whiskeye/common/message_layout.h"
#include "whiskeye/common/odometry_limits.h"
#include "whiskeye/common/se2.h"
#include "whiskeye/common/whisker_array.h"
#include "whiskeye/slam/vita_slam.h"

#include <cmath>

namespace whiskeye::slamd {
namespace {

constexpr int64_t kMaxCycleUs = 60'000'000;  // a whisk cycle's duration: far beyond any
// Plausible readings (docs/lcm-channels.md): whisker angles are within a turn either way, calibrated
// deflections within -1..1 (half again for calibration slack); odometry positions within 100 km.
constexpr double kMaxWhiskerAngle = kPi;
constexpr double kMaxDeflection = 1.5;
constexpr double kMaxOdometryPosition = 1e5;

bool finite(double v) { return std::isfinite(v); }

}  // namespace

std::string check_whisk_cycle(const whisk_cycle_t& m) {
  if (std::string bad = sample_time_error("WHISK_CYCLE", m.utime_start); !bad.empty()) return bad;
  if (std::string bad = sample_time_error("WHISK_CYCLE", m.utime_end); !bad.empty()) return bad;
  if (std::string bad = whisk_cycle_counts_error(m.num_whiskers, m.num_samples); !bad.empty()) return bad;
  if (m.utime_end < m.utime_start) return "WHISK_CYCLE: utime_end before utime_start";
  if (m.utime_end - m.utime_start > kMaxCycleUs) {
    return "WHISK_CYCLE: lasts " + std::to_string((m.utime_end - m.utime_start) / 1000) + " ms (more than 60 s)";
  }
  int missing_samples = 0;
  for (int s = 0; s < m.num_samples; ++s) {
    // The words of an error are built only for an error (a valid cycle is ~5,000 samples × 24).
    const auto at = [s] { return " at sample " + std::to_string(s); };
    // Within the cycle (so no difference of sample times can overflow), in order.
    if (m.sample_utime[s] < m.utime_start || m.sample_utime[s] > m.utime_end) {
      return "WHISK_CYCLE: sample time " + std::to_string(m.sample_utime[s]) + at() + " is outside the cycle";
    }
    if (s > 0 && m.sample_utime[s] < m.sample_utime[s - 1]) return "WHISK_CYCLE: sample times go backwards" + at();
    if (m.sample_valid[s] != 0 && m.sample_valid[s] != 1) {
      return "WHISK_CYCLE: sample_valid " + std::to_string(m.sample_valid[s]) + at() + " (0 or 1)";
    }
    if (!m.sample_valid[s]) {
      ++missing_samples;
      continue;
    }
    // Nearly every sample is good: one test of all its whiskers first (within the limits, or NaN in
    // all three values; within the limits is finite), and the whisker-by-whisker checks below only
    // to name a fault.
    const float* th = m.theta[s].data();
    const float* xs = m.deflection_x[s].data();
    const float* ys = m.deflection_y[s].data();
    bool good = true;
    for (int w = 0; w < kNumWhiskers; ++w) {
      const double theta = th[w], dx = xs[w], dy = ys[w];
      const bool within = std::abs(theta) <= kMaxWhiskerAngle && std::abs(dx) <= kMaxDeflection && std::abs(dy) <= kMaxDeflection;
      const bool unmeasured = std::isnan(theta) && std::isnan(dx) && std::isnan(dy);
      good = good && (within || unmeasured);
    }
    if (good) continue;
    for (int w = 0; w < kNumWhiskers; ++w) {
      const double theta = m.theta[s][w], dx = m.deflection_x[s][w], dy = m.deflection_y[s][w];
      // A whisker not measured in a sample is NaN in all three values (docs/lcm-channels.md).
      if (std::isnan(theta) && std::isnan(dx) && std::isnan(dy)) continue;
      const auto whisker = [&at, w] { return at() + ", whisker " + std::to_string(w); };
      if (!finite(theta) || !finite(dx) || !finite(dy)) return "WHISK_CYCLE: non-finite value" + whisker();
      if (std::abs(theta) > kMaxWhiskerAngle) {
        return "WHISK_CYCLE: theta " + std::to_string(theta) + " rad" + whisker() + " (beyond ±pi)";
      }
      if (std::abs(dx) > kMaxDeflection || std::abs(dy) > kMaxDeflection) {
        return "WHISK_CYCLE: deflection (" + std::to_string(dx) + ", " + std::to_string(dy) + ")" + whisker() +
               " (calibrated -1..1)";
      }
    }
  }
  if (m.num_missing != missing_samples) {
    return "WHISK_CYCLE: num_missing " + std::to_string(m.num_missing) + " but " + std::to_string(missing_samples) +
           " samples are marked lost";
  }
  return "";
}

std::string check_odometry(const odometry_t& m) {
  if (std::string bad = sample_time_error("ODOMETRY", m.utime); !bad.empty()) return bad;
  for (double v : {m.x, m.y, m.theta, m.vx, m.vy, m.omega}) {
    if (!finite(v)) return "ODOMETRY: non-finite value";
  }
  if (std::abs(m.x) > kMaxOdometryPosition || std::abs(m.y) > kMaxOdometryPosition) {
    return "ODOMETRY: position (" + std::to_string(m.x) + ", " + std::to_string(m.y) + ") m is beyond 100 km";
  }
  if (std::abs(m.theta) > kPi + 1e-9) {
    return "ODOMETRY: theta " + std::to_string(m.theta) + " rad is not in (-pi, pi]";
  }
  if (std::hypot(m.vx, m.vy) > kMaxOdometrySpeed || std::abs(m.omega) > kMaxOdometryTurnRate) {
    return "ODOMETRY: velocity (" + std::to_string(m.vx) + ", " + std::to_string(m.vy) + " m/s, " +
           std::to_string(m.omega) + " rad/s) beyond any base's";
  }
  return "";
}

}  // namespace whiskeye::slamd
