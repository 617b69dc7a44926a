// whiskerd's configuration (Params / load, whiskerd_core.h): unknown keys, rates, CAN id ranges, the
// shipped config.

#include <gtest/gtest.h>

#include <string>

#include "whiskeye/common/params.h"
#include "whiskeye/whiskerd/whiskerd_core.h"

using namespace whiskeye;
using namespace whiskeye::whiskerd;

TEST(WhiskerdConfig, UnknownKeyIsAnErrorNamingIt) {
  Params p;
  try {
    load(ParamNode::from_string("can:\n  intrface: can1\n"), p);
    FAIL();
  } catch (const ParamError& e) {
    EXPECT_NE(std::string(e.what()).find("can.intrface"), std::string::npos) << e.what();
  }
}

TEST(WhiskerdConfig, ClassicModeDefaultsToAFeasibleRateAndRejectsTooFast) {
  Params p;
  load(ParamNode::from_string("can: {mode: classic}\n"), p);
  EXPECT_EQ(p.mode, wp::BusMode::kClassic);
  EXPECT_EQ(p.rate_hz, 100.0);
  Params q;
  EXPECT_THROW(load(ParamNode::from_string("can: {mode: classic, rate_hz: 500}\n"), q), ParamError);
}

TEST(WhiskerdConfig, OverlappingIdRangesAreRejected) {
  Params p;
  EXPECT_THROW(load(ParamNode::from_string("can: {ids: {sample_base: 0x200}}\n"), p), ParamError);
}

TEST(WhiskerdConfig, ReceivedIdBasesMustStartAnAlignedBlockOfEight) {
  // The kernel filters cover base .. base+7 with mask 0x7f8: an unaligned base would silently drop
  // the upper boards' frames (0x183: 0x188 and 0x189).
  const std::pair<const char*, const char*> bad[] = {{"sample_base", "0x183"}, {"sample_base", "0x305"},
                                                     {"sample_base", "0x7f1"}, {"heartbeat_base", "0x703"},
                                                     {"heartbeat_base", "0x305"}, {"heartbeat_base", "0x7f1"}};
  for (const auto& [key, base] : bad) {
    Params p;
    const std::string yaml = std::string("can: {ids: {") + key + ": " + base + "}}\n";
    try {
      load(ParamNode::from_string(yaml), p);
      ADD_FAILURE() << yaml << " loaded";
    } catch (const ParamError& e) {
      EXPECT_NE(std::string(e.what()).find(std::string("can.ids.") + key), std::string::npos) << e.what();
    }
  }
  Params p;
  load(ParamNode::from_string("can: {ids: {sample_base: 0x188, heartbeat_base: 0x708}}\n"), p);
  EXPECT_EQ(p.ids.sample_base, 0x188u);
  EXPECT_EQ(p.ids.heartbeat_base, 0x708u);
}

TEST(WhiskerdConfig, ShippedConfigLoads) {
  Params p;
  load(ParamNode::from_file(WHISKEYE_SOURCE_DIR "/config/whiskerd.yaml"), p);
  EXPECT_EQ(p.interface, "can0");
  EXPECT_EQ(p.ids.command_base, 0x200u);
}
