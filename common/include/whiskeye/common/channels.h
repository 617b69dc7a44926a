// The stack's LCM channel names (docs/lcm-channels.md): one home for the defaults. A program that
// reads or writes a channel names it from here, so a reader cannot silently disagree with its
// writer about a spelling. Daemons let some names be configured (docs/lcm-channels.md); the tools
// (vita-sim, vita-eval, whiskeye-viewer, whiskeye-logcheck) use these defaults only, so they do not
// read a slamd whose output channels were renamed.
#pragma once

#include <cstddef>
#include <string_view>

namespace whiskeye::channels {

inline constexpr const char* kWhiskerSample = "WHISKER_SAMPLE";
inline constexpr const char* kRcpState = "RCP_STATE";
inline constexpr const char* kWhiskCycle = "WHISK_CYCLE";
inline constexpr const char* kCamera = "CAMERA";
inline constexpr const char* kOdometry = "ODOMETRY";
inline constexpr const char* kBaseCmd = "BASE_CMD";
inline constexpr const char* kGroundTruth = "GROUND_TRUTH";
inline constexpr const char* kSimContactTruth = "SIM_CONTACT_TRUTH";
inline constexpr const char* kSimFault = "SIM_FAULT";
inline constexpr const char* kVitaPose = "VITA_POSE";
inline constexpr const char* kVitaEvent = "VITA_EVENT";
inline constexpr const char* kVitaMatch = "VITA_MATCH";
inline constexpr const char* kVitaMap = "VITA_MAP";
inline constexpr const char* kDriverStatus = "DRIVER_STATUS";
inline constexpr const char* kSlamStatus = "SLAM_STATUS";

// The LCM type (package whiskeye) each channel carries: docs/lcm-channels.md's table. The Python
// package's `whiskeye.channels` is generated from this file at build time (python/CMakeLists.txt),
// which fails when a channel above has no entry here or an entry names no .lcm type.
struct ChannelType {
  const char* channel;
  const char* type;
};
inline constexpr ChannelType kChannelTypes[] = {
    {kWhiskerSample, "whisker_sample_t"},
    {kRcpState, "rcp_state_t"},
    {kWhiskCycle, "whisk_cycle_t"},
    {kCamera, "image_t"},
    {kOdometry, "odometry_t"},
    {kBaseCmd, "base_cmd_t"},
    {kGroundTruth, "pose2d_t"},
    {kSimContactTruth, "contact_truth_t"},
    {kSimFault, "sim_fault_t"},
    {kVitaPose, "vita_pose_t"},
    {kVitaEvent, "vita_event_t"},
    {kVitaMatch, "template_match_t"},
    {kVitaMap, "vita_map_t"},
    {kDriverStatus, "driver_status_t"},
    {kSlamStatus, "slam_status_t"},
};

// The type kChannelTypes gives `name`, or nullptr for a name the stack does not use.
constexpr const char* type_of(std::string_view name) {
  for (const ChannelType& c : kChannelTypes) {
    if (name == c.channel) return c.type;
  }
  return nullptr;
}

// LCM's longest channel name (LCM_MAX_CHANNEL_NAME_LENGTH in lcm.h): its publish refuses a longer one.
inline constexpr std::size_t kMaxNameLength = 63;

// A name a configured channel may have: 1 to kMaxNameLength of A-Z a-z 0-9 _ - /. LCM subscribes by
// regular expression ('.', '*', '|' would subscribe to other channels too); spaces, control bytes and
// non-ASCII are no one's channel, and would reach lcm-spy, the logs and the journal as they are.
constexpr bool valid_name(std::string_view name) {
  if (name.empty() || name.size() > kMaxNameLength) return false;
  for (const char c : name) {
    const bool ok = (c >= 'A' && c <= 'Z') || (c >= 'a' && c <= 'z') || (c >= '0' && c <= '9') || c == '_' || c == '-' ||
                    c == '/';
    if (!ok) return false;
  }
  return true;
}

}  // namespace whiskeye::channels
