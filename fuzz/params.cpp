// Fuzz target: every YAML parameter loader, through ParamNode as the programs call them.
// Input: byte 0 selects the loader (mod 6): slamd's config (slam:, slamd:), the robot geometry
// (robot:), whiskerd.yaml, based.yaml, the RCP controller (rcp.yaml), the whisker plant (plant:);
// the rest is the YAML text. A loader may refuse the text (ParamError naming what was wrong) but must
// not crash, hang or throw anything else. camerad's loader is not here: it lives in camerad's main.
// Seeds: fuzz/corpus/params, the files of config/ with their selector byte.
#include "whiskeye/slamd/slam_node.h"
#include "whiskeye/whiskerd/config.h"

#include "whiskeye/based/params.h"
#include "whiskeye/common/params.h"
#include "whiskeye/common/robot_geometry.h"
#include "whiskeye/rcp/params.h"
#include "whiskeye/rcp/plant.h"
#include "whiskeye/slam/vita_slam.h"

#include <cstdlib>
#include <string>

using namespace whiskeye;

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size < 1) return 0;
  const std::string yaml(reinterpret_cast<const char*>(data + 1), size - 1);
  try {
    const ParamNode root = ParamNode::from_string(yaml, "fuzz.yaml");
    switch (data[0] % 6) {
      case 0: {
        slam::SlamParams slam;
        slamd::NodeParams node;
        slam::load(root.section("slam"), slam);
        slamd::load(root.section("slamd"), node);
        break;
      }
      case 1: {
        RobotGeometry robot = default_robot_geometry();
        load(root.section("robot"), robot);
        break;
      }
      case 2: {
        whiskerd::Params p;
        whiskerd::load(root, p);
        break;
      }
      case 3: {
        based::BasedParams p;
        based::load(root, p);
        break;
      }
      case 4: {
        rcp::ControllerParams p;
        rcp::load(root, p);
        break;
      }
      case 5: {
        rcp::PlantParams p;
        rcp::load(root.section("plant"), p);
        break;
      }
    }
    root.check_no_unknown_keys();
    (void)root.dump();
  } catch (const ParamError& e) {
    if (std::string(e.what()).empty()) std::abort();
  }
  return 0;
}
