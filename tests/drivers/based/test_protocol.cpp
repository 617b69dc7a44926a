// Unit tests of based's pure parts: odometry reply and omnidrive command bodies, the base URL, a
// sample's time (protocol.h).
#include "whiskeye/based/protocol.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

namespace whiskeye::based {
namespace {

TEST(OdometryReply, ParsesTheSevenElementArray) {
  OdometrySample s;
  std::string error;
  ASSERT_TRUE(parse_odometry_reply("[1.5, -2.25, 3.0, 0.1, -0.2, 0.3, 42]", s, error)) << error;
  EXPECT_DOUBLE_EQ(s.x, 1.5);
  EXPECT_DOUBLE_EQ(s.y, -2.25);
  EXPECT_DOUBLE_EQ(s.theta, 3.0);
  EXPECT_DOUBLE_EQ(s.vx, 0.1);
  EXPECT_DOUBLE_EQ(s.vy, -0.2);
  EXPECT_DOUBLE_EQ(s.omega, 0.3);
  EXPECT_EQ(s.seq, 42);
}

TEST(OdometryReply, AcceptsSeqWrittenAsAnIntegralFloat) {
  OdometrySample s;
  std::string error;
  ASSERT_TRUE(parse_odometry_reply(" [0,0,0,0,0,0,12.0]\n", s, error)) << error;
  EXPECT_EQ(s.seq, 12);
}

struct BadReply {
  const char* body;
  const char* says;
};

class RejectsBadReply : public ::testing::TestWithParam<BadReply> {};

TEST_P(RejectsBadReply, WithAReasonNamingTheProblem) {
  OdometrySample s;
  s.x = 99.0;
  std::string error;
  EXPECT_FALSE(parse_odometry_reply(GetParam().body, s, error));
  EXPECT_NE(error.find(GetParam().says), std::string::npos) << error;
  EXPECT_EQ(s.x, 99.0) << "a rejected reply must not change the sample";
}

INSTANTIATE_TEST_SUITE_P(
    OdometryReply, RejectsBadReply,
    ::testing::Values(BadReply{"", "not JSON"}, BadReply{"[1, 2, oops", "not JSON"},
                      BadReply{"[NaN, 0, 0, 0, 0, 0, 1]", "not JSON"},
                      BadReply{"[1e999, 0, 0, 0, 0, 0, 1]", "not"},
                      BadReply{"{\"x\": 1}", "not a JSON array"},
                      BadReply{"[1.0, 2.0, 3.0]", "has 3 elements"},
                      BadReply{"[0,0,0,0,0,0,1,2]", "has 8 elements"},
                      BadReply{"[0, 0, null, 0, 0, 0, 1]", "rot is not a number"},
                      BadReply{"[0, \"1\", 0, 0, 0, 0, 1]", "y is not a number"},
                      BadReply{"[0, 0, 0, 0, 0, 0, 1.5]", "seq is not a non-negative integer"},
                      BadReply{"[0, 0, 0, 0, 0, 0, -3]", "seq is negative"},
                      BadReply{"[0, 0, 0, 0, 0, 0, 18446744073709551615]", "seq is negative or too large"},
                      // Finite but impossible (found by fuzzing): each left ODOMETRY wrong until a restart.
                      BadReply{"[1.7976931348623157e308, 0, 0, 0, 0, 0, 1]", "element x = 1.7976931348623157e+308 is beyond"},
                      BadReply{"[0, 1e20, 1, 0.2, 0, 0.1, 1]", "element y = 1e+20 is beyond any base's (100000.0)"},
                      BadReply{"[0, 0, 1e17, 0.2, 0, 0.1, 1]", "element rot = 1e+17 is beyond"},
                      BadReply{"[0.5, 0.5, 0, 1e300, 0, 0, 1]", "element vx = 1e+300 is beyond"},
                      BadReply{"[0, 0, 0, 0, 0, 5000, 1]", "element omega = 5000.0 is beyond"},
                      BadReply{"[0, \"0123456789012345678901234567890123456789xyz\", 0, 0, 0, 0, 1]",
                               "y is not a number: \"0123456789012345678901234567890123456789\"..."}));

// A reply nested 100,000 deep in an element: the error line describes it by its size (dumping it
// recursed once per level and overflowed the poll thread's stack, killing based).
TEST(OdometryReply, ADeeplyNestedElementIsRejectedWithoutRecursing) {
  const std::string deep = "[" + std::string(100000, '[') + std::string(100000, ']') + ",0,0,0,0,0,0]";
  OdometrySample s;
  std::string error;
  EXPECT_FALSE(parse_odometry_reply(deep, s, error));
  EXPECT_NE(error.find("odometry reply of 200014 bytes, more than 4 KiB"), std::string::npos) << error;
  const std::string nested = "[" + std::string(1000, '[') + std::string(1000, ']') + ",0,0,0,0,0,0]";
  EXPECT_FALSE(parse_odometry_reply(nested, s, error));
  EXPECT_NE(error.find("element x is not a number: a JSON array of 1 elements"), std::string::npos) << error;
}

TEST(OmnidriveCommand, IsAJsonArrayOfThreeNumbersThatRoundTrips) {
  const std::string body = format_omnidrive_command(0.25, -0.125, 1.0 / 3.0);
  const nlohmann::json j = nlohmann::json::parse(body);
  ASSERT_TRUE(j.is_array());
  ASSERT_EQ(j.size(), 3u);
  EXPECT_EQ(j[0].get<double>(), 0.25);
  EXPECT_EQ(j[1].get<double>(), -0.125);
  EXPECT_EQ(j[2].get<double>(), 1.0 / 3.0);
}

TEST(BaseUrl, ParsesHostAndPort) {
  BaseUrl u;
  std::string error;
  ASSERT_TRUE(parse_base_url("http://192.168.0.1:80", u, error)) << error;
  EXPECT_EQ(u.host, "192.168.0.1");
  EXPECT_EQ(u.port, 80);
  ASSERT_TRUE(parse_base_url("http://robotino/", u, error)) << error;
  EXPECT_EQ(u.host, "robotino");
  EXPECT_EQ(u.port, 80);
  ASSERT_TRUE(parse_base_url("http://127.0.0.1:8080", u, error));
  EXPECT_EQ(u.port, 8080);
}

TEST(BaseUrl, RejectsWhatItCannotUse) {
  BaseUrl u;
  std::string error;
  EXPECT_FALSE(parse_base_url("https://base", u, error));
  EXPECT_NE(error.find("http://"), std::string::npos);
  EXPECT_FALSE(parse_base_url("http://base:0", u, error));
  EXPECT_NE(error.find("bad port"), std::string::npos);
  EXPECT_FALSE(parse_base_url("http://base:99999", u, error));
  EXPECT_FALSE(parse_base_url("http://base:8x", u, error));
  EXPECT_FALSE(parse_base_url("http://:80", u, error));
  EXPECT_NE(error.find("no host"), std::string::npos);
  EXPECT_FALSE(parse_base_url("http://base/data/odometry", u, error));
  EXPECT_NE(error.find("without a path"), std::string::npos);
}

TEST(SampleUtime, IsTheMiddleOfTheRoundTrip) {
  EXPECT_EQ(sample_utime(1'000'000, 20'000), 990'000);
  EXPECT_EQ(sample_utime(1'000'000, 0), 1'000'000);
}

}  // namespace
}  // namespace whiskeye::based
