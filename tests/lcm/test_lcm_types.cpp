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
  // Names other tools rely on (vita-eval, plots, scripts): a rename fails to compile here, a
  // renumbered constant fails the test.
  pose2d_t p{};
  p.utime = 1;
  p.x = p.y = p.theta = 0.0;
  EXPECT_EQ(encode_message(p).size(), 8u + 8 + 3 * 8);
  EXPECT_EQ(vita_event_t::NEW_EXPERIENCE, 1);
  EXPECT_EQ(vita_event_t::RELOCALISE, 2);
}

TEST(LcmTypes, WhiskCycleWireLayoutIsWhatSlamdChecksBeforeDecoding) {
  // slamd checks a WHISK_CYCLE's counts against its length before decoding it (the generated decoder
  // would size its arrays first): fingerprint, 4 int64, 3 int32, then per sample 8 + 1 + 1 bytes and
  // per sample and whisker 3 floats and a byte.
  whisk_cycle_t c{};
  c.num_samples = 3;
  c.num_whiskers = 2;
  c.sample_utime = {1, 2, 3};
  c.sample_valid = {1, 1, 0};
  c.phase = {0, 1, 2};
  c.theta = c.deflection_x = c.deflection_y = {{0.5f, 0.25f}, {0.0f, 1.0f}, {2.0f, 3.0f}};
  c.contact = {{1, 0}, {0, 0}, {0, 1}};
  const std::vector<uint8_t> bytes = encode_message(c);
  EXPECT_EQ(bytes.size(), 8u + 4 * 8 + 3 * 4 + 3 * 10 + 3 * 2 * 13);
  whisk_cycle_t back;
  ASSERT_TRUE(decode_message(bytes, back));
  EXPECT_EQ(back.theta, c.theta);
  EXPECT_EQ(back.contact, c.contact);
}

}  // namespace
}  // namespace whiskeye
