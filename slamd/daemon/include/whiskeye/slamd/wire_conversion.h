// slamd's messages and the SLAM core's plain structs, each to the other: the one place that knows
// both (the core never sees an LCM type). Messages in are assumed checked (message_layout.h,
// src/message_checks.h).
#pragma once

#include "whiskeye/common/message_layout.h"
#include "whiskeye/slam/experience_map.h"
#include "whiskeye/slam/types.h"
#include "whiskeye/slam/vita_slam.h"

#include <whiskeye/odometry_t.hpp>
#include <whiskeye/template_match_t.hpp>
#include <whiskeye/vita_event_t.hpp>
#include <whiskeye/vita_map_t.hpp>
#include <whiskeye/whisk_cycle_t.hpp>

#include <cstdint>

namespace whiskeye::slamd {

// ---- wire → core ----

slam::WhiskCycleInput to_core(const whisk_cycle_t& m);
// The same into `in`, every field written, its samples' storage reused.
void to_core(const whisk_cycle_t& m, slam::WhiskCycleInput& in);
slam::OdometrySample to_core(const odometry_t& m);
// A view of the frame's pixels (valid while the frame is).
slam::ImageView to_core(const CameraFrame& f);
// Contact in a measured sample of the cycle (a lost sample's flags say nothing).
bool has_contact(const whisk_cycle_t& m);

// ---- core → wire ----

// The `mode` field of VITA_POSE, VITA_EVENT, VITA_MATCH, VITA_MAP and SLAM_STATUS.
int8_t mode_code(slam::Mode mode);
// The `localisation` field of VITA_POSE, VITA_EVENT and SLAM_STATUS.
int8_t localisation_code(bool localising);
// VITA_EVENT and VITA_MATCH of a cycle's result.
vita_event_t event_message(const slam::CycleResult& r, int64_t utime, int64_t cycle, slam::Mode mode);
template_match_t match_message(const slam::CycleResult& r, int64_t utime, int64_t cycle, slam::Mode mode);
// VITA_MAP: every experience and link of the map.
vita_map_t map_message(const slam::ExperienceMap& map, int64_t utime, slam::Mode mode);

}  // namespace whiskeye::slamd
