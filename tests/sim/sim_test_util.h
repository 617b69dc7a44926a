// Small worlds for the simulator's tests, written as YAML so the loader is exercised too.
#pragma once

#include "whiskeye/sim/world.h"

#include <gtest/gtest.h>

#include <fstream>
#include <iterator>
#include <string>

namespace whiskeye::sim::test {

inline World world_from_yaml(const std::string& body) {
  return load_world(ParamNode::from_string("world:\n" + body, "<test world>"));
}

inline std::string source_path(const std::string& rel) { return std::string(WHISKEYE_SOURCE_DIR) + "/" + rel; }

// The default arena (config/worlds/aliased_arena.yaml) with one piece of its text replaced (none
// when `from` is empty); a `from` not in the file is a test failure.
inline World arena_with(const std::string& from, const std::string& to) {
  std::ifstream in(source_path("config/worlds/aliased_arena.yaml"));
  std::string text{std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
  if (!from.empty()) {
    const auto at = text.find(from);
    EXPECT_NE(at, std::string::npos) << from;
    if (at != std::string::npos) text.replace(at, from.size(), to);
  }
  const ParamNode root = ParamNode::from_string(text, "<arena>");
  World w;
  load(root.section("world"), w);
  return w;
}

}  // namespace whiskeye::sim::test
