// What slamd checks in a decoded WHISK_CYCLE or ODOMETRY message before it reaches the synchroniser
// (docs/lcm-channels.md, the channels' contracts). What is checked before decoding, and on a camera
// frame, the viewer checks too: common/message_layout.h.
#pragma once

#include <whiskeye/odometry_t.hpp>
#include <whiskeye/whisk_cycle_t.hpp>

#include <string>

namespace whiskeye::slamd {

// Why the cycle breaks the contract (sample times, counts, the samples' order and validity flags,
// a whisker's values: all three NaN where not measured, else finite and within range), or "".
std::string check_whisk_cycle(const whisk_cycle_t& m);

// Why the sample breaks the contract (its time, non-finite values, a position beyond 100 km, a
// heading outside (-pi, pi], a velocity beyond any base's), or "".
std::string check_odometry(const odometry_t& m);

}  // namespace whiskeye::slamd
