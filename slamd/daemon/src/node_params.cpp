// slamd's node parameters (node_params.h).
#include "whiskeye/slamd/node_params.h"

namespace whiskeye::slamd {

void load(const ParamNode& node, NodeParams& p) {
  node.get("camera_tolerance_s", p.sync.camera_tolerance_s, 0.0, 2.0);
  node.get("max_wait_s", p.sync.max_wait_s, 0.05, 30.0);
  node.get("camera_buffer_s", p.sync.camera_buffer_s, 0.0, 60.0);
  node.get("camera_buffer", p.sync.camera_buffer, 1, 1000);
  node.get("max_jump_s", p.sync.max_jump_s, 1.0, 86400.0);
  node.get("odometry_buffer", p.sync.odometry_buffer, 100, 10000000);
  node.get("map_period_s", p.map_period_s, 0.0, 3600.0);
  // The same key names as whiskerd's lcm.channel_* for the same channel (channel_cycle).
  node.get("channel_cycle", p.channels.cycle);
  node.get("channel_camera", p.channels.camera);
  node.get("channel_odometry", p.channels.odometry);
  node.get("channel_pose", p.channels.pose);
  node.get("channel_event", p.channels.event);
  node.get("channel_match", p.channels.match);
  node.get("channel_map", p.channels.map);
  node.get("channel_status", p.channels.status);
}

}  // namespace whiskeye::slamd
