// whiskeye-calibrate theta on the live bus: the θ sweep through whiskerd's own control loop and
// safety state machine (see sweep.cpp). The tool's edge: devices and threads.
#pragma once

#include <functional>
#include <string>

#include "whiskeye/whiskerd/config.h"

namespace whiskeye::calibrate {

struct SweepPlan {
  double stop_rad = 0;         // the end stops at ±this; the sweep is commanded 20 deg past them
  double frequency_hz = 0.1;   // slow: ~1.6 s at each stop per cycle
  double seconds = 25.0;       // how long to whisk before retracting
  std::string interface;       // empty: whiskerd's can.interface
  bool gpio = true;            // the motor enable / fault lines (false: a rig without them)
};

struct SweepOutcome {
  std::string abort;  // why the sweep was cut short ("" if it ran its time)
};

// Whisks with whiskerd's configuration in use (`in_use`, its calibration included) changed only in
// the pattern, while `record(until)` records the bus until `until()` says so; then retracts and drops
// the enable line. Throws on a device that cannot be opened.
SweepOutcome run_sweep(const whiskerd::Params& in_use, const SweepPlan& plan,
                       const std::function<void(const std::function<bool()>&)>& record);

}  // namespace whiskeye::calibrate
