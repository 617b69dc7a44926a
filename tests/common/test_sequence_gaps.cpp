// Messages missing between sequence numbers (common/sequence_gaps.h), shared by slamd's input
// counters and whiskeye-logcheck.
#include "whiskeye/common/sequence_gaps.h"

#include <gtest/gtest.h>

#include <limits>

namespace whiskeye {
namespace {

constexpr int64_t kMin = std::numeric_limits<int64_t>::min();
constexpr int64_t kMax = std::numeric_limits<int64_t>::max();

TEST(SequenceGaps, CountsTheNumbersBetweenAndRestartsOnANumberNotAbove) {
  SequenceGaps g;
  EXPECT_EQ(g.add(1), 0);
  EXPECT_EQ(g.add(2), 0);
  EXPECT_EQ(g.add(6), 3);
  EXPECT_EQ(g.add(8), 1);
  EXPECT_EQ(g.add(3), 0);  // the sender restarted
  EXPECT_EQ(g.lost(), 4);
  EXPECT_EQ(g.places(), 2);
  EXPECT_EQ(g.longest(), 3);
  EXPECT_EQ(g.restarts(), 1);
}

// −2^63 then 2^63 − 1 (a fuzzer's input; a corrupt ODOMETRY.seq): 2^64 − 2 numbers between, more
// than int64 holds. Was "lost −2" (and signed overflow in the total): the count saturates.
TEST(SequenceGaps, AHugeGapSaturatesInsteadOfOverflowing) {
  SequenceGaps g;
  g.add(kMin);
  EXPECT_EQ(g.add(kMax), kMax);
  EXPECT_EQ(g.lost(), kMax);
  EXPECT_EQ(g.longest(), kMax);
  g.add(kMin);             // a restart
  EXPECT_EQ(g.add(10), kMax);
  EXPECT_EQ(g.lost(), kMax);  // the total saturates too
  EXPECT_EQ(g.places(), 2);
}

// A message that arrived but was refused: at its place in the sequence it is no gap; any other
// number (a stale copy, a corrupt field) changes nothing, not even at the top of the range.
TEST(SequenceGaps, ARefusedMessageAtItsPlaceIsNoGapAndAnyOtherChangesNothing) {
  SequenceGaps g;
  g.arrived(5);  // before any number: nothing to follow
  g.add(1);
  g.arrived(2);  // refused, but it came
  EXPECT_EQ(g.add(3), 0);
  g.arrived(0);     // a stale copy
  g.arrived(kMin);  // a corrupt number
  g.arrived(9);     // ahead: says nothing of 4..8
  EXPECT_EQ(g.add(4), 0);
  EXPECT_EQ(g.lost(), 0);
  EXPECT_EQ(g.restarts(), 0);
  g.add(kMax);
  g.arrived(kMin);  // kMax + 1 does not exist
  EXPECT_EQ(g.add(kMax), 0);
  EXPECT_EQ(g.restarts(), 1);
}

TEST(SequenceGaps, TheLargestNumberFollowedByNothingLargerIsARestart) {
  SequenceGaps g;
  g.add(kMax - 1);
  EXPECT_EQ(g.add(kMax), 0);  // last + 1 is computed nowhere: no overflow at the top
  EXPECT_EQ(g.add(kMax), 0);
  EXPECT_EQ(g.restarts(), 1);
  EXPECT_EQ(g.lost(), 0);
}

}  // namespace
}  // namespace whiskeye
