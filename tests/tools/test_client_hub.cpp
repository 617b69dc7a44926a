// ClientHub: the viewer's clients, bounded, and the updates broadcast to them.
#include "viewer_messages.h"

#include "whiskeye/viewer/client_hub.h"

#include <gtest/gtest.h>

#include <chrono>

namespace whiskeye::viewer {
namespace {

using namespace whiskeye::viewer::test;

TEST(ClientHub, RefusesClientsBeyondTheLimitAndCountsDropsOfClientsGone) {
  ClientHub hub(2, 1);
  auto a = hub.join();
  auto b = hub.join();
  ASSERT_NE(a, nullptr);
  ASSERT_NE(b, nullptr);
  EXPECT_EQ(hub.join(), nullptr);
  Update u;
  a->pop(u, std::chrono::milliseconds(0));  // a's first resync
  hub.broadcast(text("x"));                 // b still owes its resync: x is covered by it
  hub.broadcast(text("y"));                 // a's queue (1) is full: x and y dropped
  ClientHub::Stats s = hub.stats();
  EXPECT_EQ(s.clients, 2u);
  EXPECT_EQ(s.refused, 1);
  EXPECT_EQ(s.broadcasts, 2);
  EXPECT_EQ(s.dropped, 2);
  hub.leave(a);
  s = hub.stats();
  EXPECT_EQ(s.clients, 1u);
  EXPECT_EQ(s.dropped, 2) << "a's drops are still counted after it left";
  EXPECT_NE(hub.join(), nullptr) << "a's place is free again";
  hub.close_all();
  EXPECT_EQ(b->pop(u, std::chrono::milliseconds(1000)), ClientQueue::Next::kClosed);
  EXPECT_EQ(hub.join(), nullptr) << "no new client once stopping";
}

}  // namespace
}  // namespace whiskeye::viewer
