// Loading SlamParams from the `slam:` section of config/slam.yaml (one section per module).
#include "whiskeye/slam/vita_slam.h"

namespace whiskeye::slam {

void load(const ParamNode& node, SlamParams& p) {
  std::string mode = to_string(p.mode);
  node.get("mode", mode);
  try {
    p.mode = parse_mode(mode);
  } catch (const std::invalid_argument& e) {
    node.fail("mode", std::string("is an ") + e.what());
  }
  node.get("max_odometry_dt", p.max_odometry_dt, 1e-3, 60.0);
  node.get("path_integration_period", p.path_integration_period, 0.0, 10.0);
  load(node.section("visual"), p.visual);
  load(node.section("tactile"), p.tactile);
  load(node.section("match"), p.match);
  load(node.section("pose_cells"), p.pose_cells);
  load(node.section("experience_map"), p.experience_map);
  load(node.section("localisation"), p.localisation);
}

}  // namespace whiskeye::slam
