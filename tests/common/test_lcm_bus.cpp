// LcmBus over udpm:// (in a private network namespace, scripts/netns-run): what LCM's receive queue
// does with a burst of messages that arrived before the loop handled any of them.
#include "whiskeye/common/big_endian.h"
#include "whiskeye/common/bus.h"

#include <gtest/gtest.h>

#include <chrono>
#include <cstdint>
#include <string>
#include <thread>
#include <vector>

namespace whiskeye {
namespace {

constexpr int kBurst = 500;

// When the receiver's queue capacity is set: not at all (LCM's default), before it subscribes, after.
enum class Capacity { kLcmDefault, kSetBefore, kSetAfter };

// A receiver subscribed to `channel` is sent kBurst messages numbered 0, 1, ... while its loop
// handles none (as when the loop is busy with a cycle: its LCM thread takes them off the socket
// meanwhile); then it handles until it has them all or nothing more comes. Returns the numbers it
// delivered, in order.
std::vector<int> deliver_burst(const std::string& channel, Capacity when, int capacity = 0) {
  LcmBus receiver;
  if (when == Capacity::kSetBefore) receiver.set_queue_capacity(channel, capacity);
  std::vector<int> delivered;
  receiver.subscribe_raw(channel, [&](std::span<const uint8_t> data, const MessageInfo&) {
    delivered.push_back(data.size() == 4 ? read_be_i32(data.data()) : -1);
  });
  if (when == Capacity::kSetAfter) receiver.set_queue_capacity(channel, capacity);
  {
    LcmBus sender;
    for (int i = 0; i < kBurst; ++i) {
      const uint8_t bytes[4] = {static_cast<uint8_t>(i >> 24), static_cast<uint8_t>(i >> 16),
                                static_cast<uint8_t>(i >> 8), static_cast<uint8_t>(i)};
      sender.publish_raw(channel, bytes);
    }
  }
  std::this_thread::sleep_for(std::chrono::milliseconds(500));
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(10);
  while (static_cast<int>(delivered.size()) < kBurst && std::chrono::steady_clock::now() < deadline) {
    if (receiver.handle_timeout(500) == 0) break;
  }
  return delivered;
}

void expect_in_order(const std::vector<int>& delivered) {
  for (std::size_t i = 0; i < delivered.size(); ++i) EXPECT_EQ(delivered[i], static_cast<int>(i));
}

TEST(LcmBus, ABurstTheLoopHasNotHandledYetIsDeliveredWholeAndInOrderWithinTheQueueCapacity) {
  const std::vector<int> delivered = deliver_burst("BURST_WHOLE", Capacity::kSetBefore, kBurst);
  EXPECT_EQ(delivered.size(), static_cast<std::size_t>(kBurst));
  expect_in_order(delivered);
}

TEST(LcmBus, ACapacitySetAfterSubscribingAppliesToThatSubscription) {
  const std::vector<int> delivered = deliver_burst("BURST_LATE", Capacity::kSetAfter, 0);  // 0: no limit
  EXPECT_EQ(delivered.size(), static_cast<std::size_t>(kBurst));
  expect_in_order(delivered);
}

// Why the capacity is set: with LCM's default (30 unhandled messages per subscription) the start of
// a burst is kept and the rest dropped without a trace. If a newer LCM stops doing so, this says it.
TEST(LcmBus, WithLcmsDefaultCapacityABurstLosesAllButItsFirstThirtyOrSoWithoutATrace) {
  const std::vector<int> delivered = deliver_burst("BURST_DEFAULT", Capacity::kLcmDefault);
  EXPECT_GE(delivered.size(), 30u);
  EXPECT_LE(delivered.size(), 32u);
  expect_in_order(delivered);
}

}  // namespace
}  // namespace whiskeye
