// The simulator's pure libraries are sealed: whiskeye_sim, whiskeye_sim_can, whiskeye_sim_bringup
// and whiskeye_worldgen bring in no YAML parser (the world's loader and writer keep yaml-cpp in their
// sources), no LCM, no image codec and no command-line parser. Checked at compile time: this file
// includes every public header of theirs and fails to compile if one of them pulled in yaml-cpp,
// LCM's generated types, OpenCV's imgcodecs, libturbojpeg or CLI11. Its target links only those
// libraries, so the edges' include roots (sim/lcm, sim/plots, sim/app) are not even on its path.
// (docs/architecture.md, "The sealed core".)
#include <whiskeye/sim/alias_check.h>
#include <whiskeye/sim/bringup.h>
#include <whiskeye/sim/can_log.h>
#include <whiskeye/sim/odometry.h>
#include <whiskeye/sim/renderer.h>
#include <whiskeye/sim/simulator.h>
#include <whiskeye/sim/whisker_contact.h>
#include <whiskeye/sim/world.h>
#include <whiskeye/sim/world_generator.h>
#include <whiskeye/sim/world_writer.h>

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>

#ifdef YAML_CPP_API
#error "a pure sim header includes yaml-cpp: keep it behind ParamNode (common/params.h) and in world_writer.cpp"
#endif
#ifdef _LCM_LIB_INLINE_H
#error "a pure sim header includes LCM: the LCM messages are whiskeye_sim_lcm's (sim/lcm)"
#endif
#ifdef OPENCV_IMGCODECS_HPP
#error "a pure sim header includes OpenCV's imgcodecs"
#endif
#ifdef __TURBOJPEG_H__
#error "a pure sim header includes libturbojpeg: MJPEG frames are encoded in whiskeye_sim_lcm"
#endif
#ifdef CLI11_VERSION
#error "a pure sim header includes CLI11: vita-sim's options are whiskeye_sim_app's (sim/app)"
#endif

namespace {

// A public header added to a pure library is added above too.
TEST(SealedSim, EveryPublicHeaderOfThePureLibrariesIsIncludedHere) {
  std::ifstream self(std::string(WHISKEYE_SOURCE_DIR) + "/tests/sim/test_sealed_sim.cpp");
  const std::string text{std::istreambuf_iterator<char>(self), std::istreambuf_iterator<char>()};
  ASSERT_FALSE(text.empty());
  int headers = 0;
  for (const char* root : {"sim/include", "sim/can/include", "sim/bringup/include", "sim/worldgen/include"}) {
    const std::filesystem::path dir = std::filesystem::path(WHISKEYE_SOURCE_DIR) / root / "whiskeye/sim";
    for (const auto& entry : std::filesystem::directory_iterator(dir)) {
      const std::string name = entry.path().filename().string();
      EXPECT_NE(text.find("#include <whiskeye/sim/" + name + ">"), std::string::npos) << root << "/whiskeye/sim/" << name;
      ++headers;
    }
  }
  EXPECT_GE(headers, 10) << "the four include roots were found";
}

}  // namespace
