// Names of the wire codes of slamd's messages (docs/lcm-channels.md), for what people read: reports,
// JSON, the viewer's page. One home, so every tool spells a mode or an event alike. Needs the
// generated LCM types (whiskeye_bus or whiskeye_lcmtypes).
#pragma once

#include <whiskeye/vita_event_t.hpp>
#include <whiskeye/vita_pose_t.hpp>

#include <cstdint>

namespace whiskeye {

// vita_pose_t::MODE_* (also the `mode` of VITA_EVENT, VITA_MATCH, VITA_MAP, SLAM_STATUS):
// "visual", "tactile", "vita", or "unknown" for a code outside the contract.
inline const char* mode_name(int8_t mode) {
  switch (mode) {
    case vita_pose_t::MODE_VISUAL: return "visual";
    case vita_pose_t::MODE_TACTILE: return "tactile";
    case vita_pose_t::MODE_VITA: return "vita";
  }
  return "unknown";
}

// vita_event_t's type: "same", "new", "relocalise", or "unknown".
inline const char* event_type_name(int8_t type) {
  switch (type) {
    case vita_event_t::SAME_EXPERIENCE: return "same";
    case vita_event_t::NEW_EXPERIENCE: return "new";
    case vita_event_t::RELOCALISE: return "relocalise";
  }
  return "unknown";
}

}  // namespace whiskeye
