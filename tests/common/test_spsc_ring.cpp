// The lock-free single-producer single-consumer ring (spsc_ring.h): whiskerd's control thread hands
// each period to its publisher thread through it.

#include <gtest/gtest.h>

#include <array>
#include <atomic>
#include <cstdint>
#include <thread>

#include "whiskeye/common/spsc_ring.h"

using namespace whiskeye;

TEST(SpscRing, DropsWhenFullInsteadOfBlocking) {
  SpscRing<int, 4> ring;
  for (int i = 0; i < 4; ++i) EXPECT_TRUE(ring.try_push(i));
  int x = 99;
  EXPECT_FALSE(ring.try_push(x));
  int out = -1;
  EXPECT_TRUE(ring.try_pop(out));
  EXPECT_EQ(out, 0);
  EXPECT_TRUE(ring.try_push(x));
  for (int want : {1, 2, 3, 99}) {
    ASSERT_TRUE(ring.try_pop(out));
    EXPECT_EQ(out, want);
  }
  EXPECT_FALSE(ring.try_pop(out));
}

// The control thread and the publisher thread at full speed: every item arrives once, in order,
// whole (each carries a checksum over its payload), and nothing is lost but what try_push refused.
TEST(SpscRing, TwoThreadsHandOverEveryItemInOrderAndWhole) {
  struct Item {
    int64_t seq = -1;
    std::array<int64_t, 15> payload{};
    int64_t sum = 0;
  };
  SpscRing<Item, 64> ring;
  constexpr int64_t kItems = 300000;
  std::atomic<int64_t> refused{0};
  std::thread producer([&] {
    for (int64_t i = 0; i < kItems; ++i) {
      Item it;
      it.seq = i;
      for (std::size_t k = 0; k < it.payload.size(); ++k) it.payload[k] = i * 31 + static_cast<int64_t>(k);
      for (int64_t v : it.payload) it.sum += v;
      if (!ring.try_push(it)) refused.fetch_add(1, std::memory_order_relaxed);
    }
  });
  int64_t received = 0, last = -1, torn = 0, reordered = 0;
  Item out;
  while (true) {
    if (ring.try_pop(out)) {
      ++received;
      int64_t sum = 0;
      for (int64_t v : out.payload) sum += v;
      torn += sum != out.sum || out.payload[0] != out.seq * 31;
      reordered += out.seq <= last;
      last = out.seq;
    } else if (last == kItems - 1 || (received + refused.load() == kItems && ring.size() == 0)) {
      break;
    }
  }
  producer.join();
  EXPECT_EQ(torn, 0);
  EXPECT_EQ(reordered, 0);
  EXPECT_EQ(received + refused.load(), kItems);
  EXPECT_GT(received, 0);
}
