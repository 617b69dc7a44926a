// Small worlds for the simulator's tests, written as YAML so the loader is exercised too.
#pragma once

#include "whiskeye/sim/world.h"

#include <string>

namespace whiskeye::sim::test {

inline World world_from_yaml(const std::string& body) {
  const ParamNode root = ParamNode::from_string("world:\n" + body, "<test world>");
  World w;
  load(root.section("world"), w);
  root.check_no_unknown_keys();
  return w;
}

inline std::string source_path(const std::string& rel) { return std::string(WHISKEYE_SOURCE_DIR) + "/" + rel; }

}  // namespace whiskeye::sim::test
