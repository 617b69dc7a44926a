// Unit checks of the message contract itself (no transport).
#include "samples.h"

#include "whiskeye/common/bus.h"

#include <whiskeye/pose2d_t.hpp>
#include <whiskeye/vita_event_t.hpp>
#include <whiskeye/whisk_cycle_t.hpp>

#include <gtest/gtest.h>

#include <set>
#include <sstream>

namespace whiskeye {
namespace {

TEST(LcmTypes, EverySampleCoversEveryDefinedType) {
  std::set<std::string> defined;
  std::stringstream ss(WHISKEYE_LCM_TYPE_LIST);
  for (std::string t; std::getline(ss, t, ';');) defined.insert(t);
  std::set<std::string> sampled;
  for (const auto& s : testing::all_type_samples()) sampled.insert(s.type);
  EXPECT_EQ(sampled, defined) << "a .lcm type was added without a sample in tests/lcm/samples.cpp";
}

TEST(LcmTypes, EverySampleRoundTripsInMemory) {
  for (const auto& s : testing::all_type_samples()) EXPECT_TRUE(s.round_trips(s.bytes)) << s.type;
}

TEST(LcmTypes, ContractFieldNamesAndConstants) {
  // Names other tools rely on (vita-eval, plots, scripts): a rename must fail here.
  pose2d_t p{};
  p.utime = 1;
  p.x = p.y = p.theta = 0.0;
  EXPECT_EQ(vita_event_t::NEW_EXPERIENCE, 1);
  EXPECT_EQ(vita_event_t::RELOCALISE, 2);
  whisk_cycle_t c{};
  c.num_samples = 1;
  c.num_whiskers = 2;
  c.theta = {{0.0f, 0.0f}};
  EXPECT_EQ(c.theta[0].size(), 2u);
}

}  // namespace
}  // namespace whiskeye
