// ClientQueue: one client's bounded queue of updates, and its resync when it falls behind.
#include "viewer_messages.h"

#include "whiskeye/viewer/client_hub.h"

#include <gtest/gtest.h>

#include <chrono>
#include <string>

namespace whiskeye::viewer {
namespace {

using namespace whiskeye::viewer::test;

TEST(ClientQueue, ANewClientIsSentTheWholeStateFirst) {
  ClientQueue q(1, 4);
  Update u;
  EXPECT_EQ(q.pop(u, std::chrono::milliseconds(0)), ClientQueue::Next::kResync);
  EXPECT_EQ(q.pop(u, std::chrono::milliseconds(0)), ClientQueue::Next::kTimeout);
  q.push(text("a"));
  q.push(text("b"));
  ASSERT_EQ(q.pop(u, std::chrono::milliseconds(0)), ClientQueue::Next::kUpdate);
  EXPECT_EQ(*u, "a");
  ASSERT_EQ(q.pop(u, std::chrono::milliseconds(0)), ClientQueue::Next::kUpdate);
  EXPECT_EQ(*u, "b");
  q.close();
  EXPECT_EQ(q.pop(u, std::chrono::milliseconds(1000)), ClientQueue::Next::kClosed);
}

TEST(ClientQueue, ASlowClientDropsOldUpdatesCountedAndIsSentTheWholeStateInstead) {
  ClientQueue q(1, 4);
  Update u;
  ASSERT_EQ(q.pop(u, std::chrono::milliseconds(0)), ClientQueue::Next::kResync);
  for (int i = 0; i < 4; ++i) EXPECT_TRUE(q.push(text(std::to_string(i))));
  EXPECT_FALSE(q.push(text("4"))) << "the fifth does not fit";
  EXPECT_EQ(q.dropped(), 5) << "the four queued and the fifth";
  EXPECT_TRUE(q.push(text("5"))) << "covered by the resync still to be sent";
  EXPECT_EQ(q.pop(u, std::chrono::milliseconds(0)), ClientQueue::Next::kResync);
  EXPECT_EQ(q.pop(u, std::chrono::milliseconds(0)), ClientQueue::Next::kTimeout) << "nothing older follows it";
  q.push(text("6"));
  ASSERT_EQ(q.pop(u, std::chrono::milliseconds(0)), ClientQueue::Next::kUpdate);
  EXPECT_EQ(*u, "6");
  EXPECT_EQ(q.resyncs(), 1);
  EXPECT_EQ(q.sent(), 3);
}

}  // namespace
}  // namespace whiskeye::viewer
