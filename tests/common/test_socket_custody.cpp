// Socket custody (socket_custody.h): a socket that went down handed from the real-time thread to the
// one that reopens it, with backoff, and back.

#include <gtest/gtest.h>

#include <atomic>
#include <cstdint>
#include <memory>
#include <thread>
#include <vector>

#include "whiskeye/common/socket_custody.h"

using namespace whiskeye;

// A socket whose reopen() follows a script: false for the first `failures` calls, then true.
struct ScriptedSocket {
  int failures = 0;
  int attempts = 0;
  int64_t generation = 0;  // written by whoever reopens, read by the control thread after take_back
  bool reopen() {
    ++attempts;
    if (attempts <= failures) return false;
    ++generation;
    return true;
  }
};
using Custody = SocketCustody<ScriptedSocket>;

TEST(SocketCustody, ReopensAtOnceThenBacksOffAndHandsTheSameSocketBack) {
  Custody custody;
  auto sock = std::make_unique<ScriptedSocket>();
  sock->failures = 2;
  const ScriptedSocket* const original = sock.get();
  EXPECT_EQ(custody.service(0), Custody::Attempt::kNone);  // nothing given up yet

  custody.give_up(sock);
  EXPECT_EQ(sock, nullptr);
  EXPECT_FALSE(custody.take_back(sock));
  EXPECT_EQ(custody.service(1000), Custody::Attempt::kFailed);  // the first try is immediate
  EXPECT_EQ(custody.held(), original);
  EXPECT_EQ(custody.service(1000 + Custody::kFirstBackoffUs - 1), Custody::Attempt::kNone);
  EXPECT_EQ(custody.service(1000 + Custody::kFirstBackoffUs), Custody::Attempt::kFailed);
  const int64_t third = 1000 + 3 * Custody::kFirstBackoffUs;  // the backoff doubled
  EXPECT_EQ(custody.service(third - 1), Custody::Attempt::kNone);
  EXPECT_FALSE(custody.take_back(sock));
  EXPECT_EQ(custody.service(third), Custody::Attempt::kReopened);
  EXPECT_EQ(custody.held(), nullptr);
  EXPECT_EQ(custody.service(third + 10 * Custody::kMaxBackoffUs), Custody::Attempt::kNone);

  ASSERT_TRUE(custody.take_back(sock));
  EXPECT_EQ(sock.get(), original);  // filters, buffer size and counters travel with it
  EXPECT_EQ(sock->attempts, 3);
  EXPECT_FALSE(custody.take_back(sock));

  // The next outage starts again with an immediate try and the first backoff.
  sock->failures = 4;
  custody.give_up(sock);
  EXPECT_EQ(custody.service(50000000), Custody::Attempt::kFailed);
  EXPECT_EQ(custody.next_attempt_us(), 50000000 + Custody::kFirstBackoffUs);
}

TEST(SocketCustody, TheBackoffStopsGrowingAtItsMaximum) {
  Custody custody;
  auto sock = std::make_unique<ScriptedSocket>();
  sock->failures = 1000;
  custody.give_up(sock);
  int64_t now = 0;
  int64_t last_gap = 0;
  for (int i = 0; i < 20; ++i) {
    ASSERT_EQ(custody.service(now), Custody::Attempt::kFailed);
    last_gap = custody.next_attempt_us() - now;
    EXPECT_LE(last_gap, Custody::kMaxBackoffUs);
    now = custody.next_attempt_us();
  }
  EXPECT_EQ(last_gap, Custody::kMaxBackoffUs);
}

// A socket that reports itself down right after every reopen (an interface that flaps) is reopened
// once per backoff, not once per control period; once it stays up, the next outage starts afresh.
TEST(SocketCustody, ASocketDownAgainRightAfterItsReopenKeepsItsBackoff) {
  Custody custody;
  auto sock = std::make_unique<ScriptedSocket>();
  std::vector<int64_t> reopens;
  int64_t now = 0;
  custody.give_up(sock);
  for (; now <= 4000000; now += 2000) {  // a 500 Hz loop for 4 s: give up whatever comes back
    if (custody.service(now) == Custody::Attempt::kReopened) reopens.push_back(now);
    if (custody.take_back(sock)) custody.give_up(sock);
  }
  const std::vector<int64_t> expected{0, 100000, 300000, 700000, 1500000, 3100000};
  EXPECT_EQ(reopens, expected);

  // Back for good: taken back and kept for 5 s, then down again -> an immediate try.
  while (!custody.take_back(sock)) custody.service(now += 2000);
  now += Custody::kMaxBackoffUs;
  custody.give_up(sock);
  EXPECT_EQ(custody.service(now), Custody::Attempt::kReopened);
}

// The control loop gives its socket up and takes it back while the publisher thread reopens it,
// over and over: the socket is never lost or duplicated, and what the reopening thread wrote into it
// is what the control thread reads (run under ThreadSanitizer in scripts/test).
TEST(SocketCustody, TwoThreadsPassTheSocketBackAndForthWithoutLosingIt) {
  Custody custody;
  auto sock = std::make_unique<ScriptedSocket>();
  const ScriptedSocket* const original = sock.get();
  constexpr int kOutages = 2000;
  std::atomic<bool> done{false};
  std::thread reopener([&] {
    int64_t now = 0;
    while (!done.load()) custody.service(now += Custody::kMaxBackoffUs);  // every try is due
  });
  int64_t generations_seen = 0;
  for (int i = 0; i < kOutages; ++i) {
    custody.give_up(sock);
    while (!custody.take_back(sock)) std::this_thread::yield();
    ASSERT_EQ(sock.get(), original);
    generations_seen += sock->generation == i + 1;
  }
  done.store(true);
  reopener.join();
  EXPECT_EQ(generations_seen, kOutages);
  EXPECT_EQ(sock->attempts, kOutages);
}
