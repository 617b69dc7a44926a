// slamd's node parameters: the `slamd:` section of slam.yaml (cycle synchronisation, the map's
// throttle, the channels' names).
#pragma once

#include "whiskeye/slamd/cycle_sync.h"

#include "whiskeye/common/channels.h"
#include "whiskeye/common/params.h"

#include <string>

namespace whiskeye::slamd {

// The channels the node reads and writes. A renamed channel must be renamed at both ends: e.g.
// whiskerd.yaml's lcm.channel_cycle and slam.yaml's slamd.channel_cycle (docs/lcm-channels.md).
struct NodeChannels {
  std::string cycle = channels::kWhiskCycle;
  std::string camera = channels::kCamera;
  std::string odometry = channels::kOdometry;
  std::string pose = channels::kVitaPose;
  std::string event = channels::kVitaEvent;
  std::string match = channels::kVitaMatch;
  std::string map = channels::kVitaMap;
  std::string status = channels::kSlamStatus;
  bool operator==(const NodeChannels&) const = default;
};

struct NodeParams {
  SyncParams sync;
  double map_period_s = 1.0;  // VITA_MAP throttle, data time
  NodeChannels channels;
  bool operator==(const NodeParams&) const = default;
};
// Also refuses (ParamError naming the key) a channel name that is no LCM name of ours
// (channels::valid_name), that another of the eight channels has, or that is the stack's channel of
// another type (GROUND_TRUTH, SIM_FAULT, DRIVER_STATUS, ...: channels::kChannelTypes).
void load(const ParamNode& node, NodeParams& params);

}  // namespace whiskeye::slamd
