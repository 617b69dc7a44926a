// A simulated robot's bring-up session straight into whiskeye-calibrate's Recording: the session's
// samples (sim/bringup.h) through the boards' frames (sim::BoardTraffic) with a drawn true
// calibration, as whiskerd would receive them. For the calibration tests.
#pragma once

#include <vector>

#include "whiskeye/calibrate/recording.h"
#include "whiskeye/sim/bringup.h"
#include "whiskeye/sim/can_log.h"
#include "whiskeye/whiskerd/config.h"

namespace whiskeye::calibrate::test {

inline sim::BoardTrafficParams traffic_of(const sim::TrueCalibration& truth, wp::BusMode mode, double rate_hz) {
  sim::BoardTrafficParams traffic;
  traffic.mode = mode;
  traffic.rate_hz = rate_hz;
  traffic.calibration = truth.calibration;
  traffic.channel = truth.channel;
  return traffic;
}

// The session's frames as whiskerd would receive them from a robot calibrated as `truth`.
inline std::vector<sim::CanFrame> frames_of(const sim::SessionParams& session, const sim::TrueCalibration& truth,
                                             wp::BusMode mode = wp::BusMode::kFd) {
  sim::BoardTraffic traffic(traffic_of(truth, mode, session.rate_hz));
  std::vector<sim::CanFrame> frames;
  sim::run_session(session, [&](const rcp::WhiskerSample& s, const sim::WhiskerHealth& h) { traffic.add(s, h, frames); });
  return frames;
}

inline Recording record(const sim::SessionParams& session, const sim::TrueCalibration& truth,
                        wp::BusMode mode = wp::BusMode::kFd) {
  Recording r(mode, wp::ProtocolIds{});
  for (const sim::CanFrame& f : frames_of(session, truth, mode)) r.add_frame(f.utime, f.id, f.fd, f.data);
  return r;
}

// whiskerd's calibration as a robot fresh out of the box has it: the defaults, or the true wiring.
inline whiskerd::CoreParams defaults() { return whiskerd::CoreParams{}; }
inline whiskerd::CoreParams wired_as(const sim::TrueCalibration& truth) {
  whiskerd::CoreParams p;
  p.channel = truth.channel;
  return p;
}

}  // namespace whiskeye::calibrate::test
