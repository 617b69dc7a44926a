// Unit tests of based's parameters: the shipped config, unknown and out-of-range keys (params.h).
#include "whiskeye/based/params.h"

#include <gtest/gtest.h>

namespace whiskeye::based {
namespace {

TEST(BasedParams, ShippedConfigLoads) {
  BasedParams p;
  load(ParamNode::from_file(WHISKEYE_SOURCE_DIR "/config/based.yaml"), p);
  EXPECT_EQ(p.url, "http://192.168.0.1:80");
  EXPECT_DOUBLE_EQ(p.odometry.poll_rate_hz, 50.0);
}

TEST(BasedParams, UnknownOrOutOfRangeKeysAreErrorsNamingTheKey) {
  BasedParams p;
  try {
    load(ParamNode::from_string("command:\n  deadman: 0.3\n"), p);
    FAIL();
  } catch (const ParamError& e) {
    EXPECT_NE(std::string(e.what()).find("command.deadman"), std::string::npos) << e.what();
  }
  try {
    load(ParamNode::from_string("command:\n  rate_hz: 2\n"), p);
    FAIL();
  } catch (const ParamError& e) {
    EXPECT_NE(std::string(e.what()).find("command.rate_hz"), std::string::npos) << e.what();
  }
  try {
    load(ParamNode::from_string("url: https://192.168.0.1\n"), p);
    FAIL();
  } catch (const ParamError& e) {
    EXPECT_NE(std::string(e.what()).find("url: "), std::string::npos) << e.what();
  }
  EXPECT_THROW(check_url("192.168.0.1:80", "--url"), ParamError);
  EXPECT_NO_THROW(check_url("http://192.168.0.1:80", "--url"));
  BasedParams fresh;
  load(ParamNode::from_string("odometry:\n  poll_rate_hz: 100\n"), fresh);
  EXPECT_DOUBLE_EQ(fresh.odometry.poll_rate_hz, 100.0);
}

}  // namespace
}  // namespace whiskeye::based
