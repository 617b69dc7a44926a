// The transport seam's in-process bus (MemoryBus, typed publish / subscribe, decode errors) and the
// UDP drop count; the LCM log files: test_log_reader.cpp.
#include "whiskeye/common/bus.h"

#include <whiskeye/driver_status_t.hpp>
#include <whiskeye/odometry_t.hpp>
#include <whiskeye/pose2d_t.hpp>

#include <gtest/gtest.h>

#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <memory>
#include <vector>

namespace whiskeye {
namespace {

TEST(MemoryBus, DeliversTypedMessagesToMatchingChannels) {
  MemoryBus bus;
  DecodeErrors errors;
  std::vector<double> got;
  subscribe<pose2d_t>(bus, "GROUND_.*", [&](const pose2d_t& m) { got.push_back(m.x); }, errors);
  pose2d_t p{};
  p.x = 1.5;
  publish(bus, "GROUND_TRUTH", p);
  publish(bus, "OTHER", p);
  ASSERT_EQ(got.size(), 1u);
  EXPECT_DOUBLE_EQ(got[0], 1.5);
  EXPECT_EQ(errors.total(), 0);
}

TEST(MemoryBus, CountsDecodeFailuresInsteadOfCrashing) {
  MemoryBus bus;
  DecodeErrors errors;
  std::string last_reason;
  errors.set_callback([&](const std::string&, const std::string& reason) { last_reason = reason; });
  int delivered = 0;
  subscribe<pose2d_t>(bus, "GROUND_TRUTH", [&](const pose2d_t&) { ++delivered; }, errors);

  odometry_t wrong_type{};
  publish(bus, "GROUND_TRUTH", wrong_type);  // fingerprint mismatch
  const std::vector<uint8_t> garbage{1, 2, 3};
  bus.publish_raw("GROUND_TRUTH", garbage);  // truncated
  std::vector<uint8_t> trailing = encode_message(pose2d_t{});
  trailing.push_back(0);
  bus.publish_raw("GROUND_TRUTH", trailing);

  EXPECT_EQ(delivered, 0);
  EXPECT_EQ(errors.total(), 3);
  EXPECT_EQ(errors.count("GROUND_TRUTH"), 3);
  EXPECT_NE(last_reason.find("trailing bytes"), std::string::npos);
  EXPECT_NE(last_reason.find("whiskeye.pose2d_t"), std::string::npos);
}

TEST(MemoryBus, ANegativeArrayCountIsADecodeErrorNotAnException) {
  // The generated decoder resizes its arrays from the count before it looks at the length.
  driver_status_t st{};
  std::vector<uint8_t> bytes = encode_message(st);
  constexpr std::size_t kNumCounters = 8 + 8 + 5 + 1 + 5;  // fingerprint, utime, "", state, ""
  ASSERT_EQ(bytes.size(), kNumCounters + 4 + 4);
  std::fill(bytes.begin() + kNumCounters, bytes.begin() + kNumCounters + 4, 0xff);  // -1
  driver_status_t out;
  std::string reason;
  EXPECT_FALSE(decode_message(bytes, out, &reason));
  EXPECT_NE(reason.find("whiskeye.driver_status_t"), std::string::npos) << reason;
  EXPECT_NE(reason.find("negative or too large"), std::string::npos) << reason;

  MemoryBus bus;
  DecodeErrors errors;
  subscribe<driver_status_t>(bus, "STATUS", [](const driver_status_t&) { FAIL(); }, errors);
  bus.publish_raw("STATUS", bytes);
  EXPECT_EQ(errors.total(), 1);
}

TEST(MemoryBus, PlainNamesMatchExactlyAndRegexesAsRegexes) {
  EXPECT_TRUE(is_plain_channel_name("WHISK_CYCLE"));
  EXPECT_FALSE(is_plain_channel_name("VITA_.*"));
  MemoryBus bus;
  DecodeErrors errors;
  int exact = 0;
  int regex = 0;
  subscribe<pose2d_t>(bus, "POSE", [&](const pose2d_t&) { ++exact; }, errors);
  subscribe<pose2d_t>(bus, "POSE|POSE_B", [&](const pose2d_t&) { ++regex; }, errors);
  publish(bus, "POSE", pose2d_t{});
  publish(bus, "POSE_B", pose2d_t{});
  publish(bus, "POSEX", pose2d_t{});
  EXPECT_EQ(exact, 1);
  EXPECT_EQ(regex, 2);
}

TEST(UdpReceiveDrops, ReadsTheDropsColumnOfTheGivenSockets) {
  const std::string table =
      "   sl  local_address rem_address   st tx_queue rx_queue tr tm->when retrnsmt   uid  timeout inode ref pointer drops\n"
      "  1: 00000000:1DF3 00000000:0000 07 00000000:00000000 00:00000000 00000000     0        0 4242 2 0000000000000000 17\n"
      "  2: 0100007F:A1B2 00000000:0000 07 00000000:00000000 00:00000000 00000000     0        0 555 2 0000000000000000 9\n"
      "  3: 0100007F:A1B3 00000000:0000 07 00000000:00000000 00:00000000 00000000     0        0 777 2 0000000000000000 5\n";
  EXPECT_EQ(udp_receive_drops(table, {4242, 777}), 22);
  EXPECT_EQ(udp_receive_drops(table, {}), 0);
  EXPECT_EQ(udp_receive_drops("garbage", {1}), 0);
}

// LCM 1.3.1 counts nothing it loses; datagrams the kernel drops on a full receive buffer are what a
// daemon can see (docs/lcm-channels.md). A socket nobody reads, flooded: its drops are counted.
TEST(UdpReceiveDrops, CountsWhatTheKernelDroppedOnThisProcesssSockets) {
  const int64_t before = udp_receive_drops();
  ASSERT_GE(before, 0) << "/proc/self/net/udp unreadable";
  const int rx = ::socket(AF_INET, SOCK_DGRAM, 0);
  const int tx = ::socket(AF_INET, SOCK_DGRAM, 0);
  const int small = 4096;
  ::setsockopt(rx, SOL_SOCKET, SO_RCVBUF, &small, sizeof small);
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  ASSERT_EQ(::bind(rx, reinterpret_cast<sockaddr*>(&a), sizeof a), 0);
  socklen_t len = sizeof a;
  ::getsockname(rx, reinterpret_cast<sockaddr*>(&a), &len);
  const std::vector<char> datagram(1000, 'x');
  for (int i = 0; i < 200; ++i) {
    ::sendto(tx, datagram.data(), datagram.size(), 0, reinterpret_cast<sockaddr*>(&a), sizeof a);
  }
  const int64_t after = udp_receive_drops();
  ::close(rx);
  ::close(tx);
  EXPECT_GE(after - before, 150) << "200 datagrams of 1 kB into a 4 kB buffer";
}

TEST(MemoryBus, PublishSharedHandsTheOwnerToHandlers) {
  MemoryBus bus;
  std::vector<const void*> owners;
  bus.subscribe_raw("X", [&](std::span<const uint8_t>, const MessageInfo& info) { owners.push_back(info.data_owner.get()); });
  const auto owner = std::make_shared<const std::vector<uint8_t>>(3, 7);
  bus.publish_shared("X", *owner, owner);
  bus.publish_raw("X", *owner);
  EXPECT_EQ(owners, (std::vector<const void*>{owner.get(), nullptr}));
}

}  // namespace
}  // namespace whiskeye
