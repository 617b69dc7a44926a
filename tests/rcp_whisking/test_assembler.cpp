// Whisk-cycle assembler: one complete cycle per period, gaps marked (never invented), rejections.
#include <gtest/gtest.h>
#include <whiskeye/rcp/cycle_assembler.h>

#include <cmath>

#include "helpers.h"

using namespace whiskeye::rcp;
using whiskeye::rcp::test::kPeriodUs;
using whiskeye::rcp::test::kStartUtime;
using whiskeye::rcp::test::make_sample;

namespace {

// 1 Hz at 500 Hz: cycle k (from 1) covers seq [(k-1)*500, k*500); first half protraction.
CycleTag tag_for(int64_t seq) {
  CycleTag t;
  t.cycle = seq / 500 + 1;
  t.cycle_start_utime = kStartUtime + (seq / 500) * 500 * kPeriodUs;
  t.retract_start_utime = t.cycle_start_utime + 250 * kPeriodUs;
  t.phase = (seq % 500) < 250 ? Phase::Protract : Phase::Retract;
  return t;
}

}  // namespace

TEST(CycleAssembler, EmitsExactlyOneCycleOfAllSamplesPerPeriod) {
  CycleAssembler a;
  PerWhisker<bool> contact{};
  std::vector<WhiskCycle> cycles;
  for (int64_t seq = 0; seq < 5 * 500 + 1; ++seq) {
    WhiskerSample s = make_sample(seq, 0.01 * static_cast<double>(seq % 7), -0.02);
    s.theta[4] = 0.001 * static_cast<double>(seq);
    contact[2] = seq % 2 == 0;
    if (auto c = a.push(s, tag_for(seq), contact)) cycles.push_back(std::move(*c));
  }
  ASSERT_EQ(cycles.size(), 5u);
  for (std::size_t i = 0; i < cycles.size(); ++i) {
    const WhiskCycle& c = cycles[i];
    EXPECT_EQ(c.cycle, static_cast<int64_t>(i) + 1);
    ASSERT_EQ(c.samples.size(), 500u);
    EXPECT_EQ(c.num_missing, 0);
    EXPECT_EQ(c.utime_start, kStartUtime + static_cast<int64_t>(i) * 500 * kPeriodUs);
    EXPECT_EQ(c.utime_end, c.utime_start + 499 * kPeriodUs);
    for (int k = 0; k < 500; ++k) {
      const int64_t seq = static_cast<int64_t>(i) * 500 + k;
      const auto& s = c.samples[k];
      EXPECT_TRUE(s.valid);
      EXPECT_EQ(s.utime, kStartUtime + seq * kPeriodUs);
      EXPECT_EQ(s.phase, k < 250 ? Phase::Protract : Phase::Retract);
      EXPECT_FLOAT_EQ(s.theta[4], static_cast<float>(0.001 * static_cast<double>(seq)));
      EXPECT_FLOAT_EQ(s.deflection_x[0], static_cast<float>(0.01 * static_cast<double>(seq % 7)));
      EXPECT_FLOAT_EQ(s.deflection_y[23], -0.02f);
      EXPECT_EQ(s.contact[2], seq % 2 == 0);
    }
  }
}

TEST(CycleAssembler, MarksLostSamplesAsInvalidAtTheirExpectedTimes) {
  CycleAssembler a;
  PerWhisker<bool> contact{};
  std::optional<WhiskCycle> done;
  for (int64_t seq = 0; seq <= 500; ++seq) {
    if (seq >= 100 && seq < 103) continue;  // three lost samples
    if (seq == 300) continue;               // and one more
    auto c = a.push(make_sample(seq, 0.3, 0.3), tag_for(seq), contact);
    if (c) done = std::move(c);
  }
  ASSERT_TRUE(done.has_value());
  ASSERT_EQ(done->samples.size(), 500u);
  EXPECT_EQ(done->num_missing, 4);
  for (int k = 0; k < 500; ++k) {
    const auto& s = done->samples[k];
    EXPECT_EQ(s.utime, kStartUtime + k * kPeriodUs) << k;
    const bool lost = (k >= 100 && k < 103) || k == 300;
    EXPECT_EQ(s.valid, !lost) << k;
    if (lost) {
      // Never invented: zero values.
      EXPECT_EQ(s.deflection_x[0], 0.0f);
      EXPECT_EQ(s.theta[0], 0.0f);
      EXPECT_EQ(s.phase, k < 250 ? Phase::Protract : Phase::Retract);
    }
  }
}

TEST(CycleAssembler, AWhiskerNotMeasuredInASampleIsNaNNotZero) {
  CycleAssembler a;
  PerWhisker<bool> contact{};
  std::vector<WhiskCycle> cycles;
  for (int64_t seq = 0; seq < 500 + 1; ++seq) {
    WhiskerSample s = make_sample(seq, 0.3, 0.1);
    if (seq == 100) s.valid[7] = false;  // its board was stale this period
    if (auto c = a.push(s, tag_for(seq), contact)) cycles.push_back(std::move(*c));
  }
  ASSERT_EQ(cycles.size(), 1u);
  const auto& missing = cycles[0].samples[100];
  EXPECT_TRUE(missing.valid) << "the sample itself was measured";
  EXPECT_TRUE(std::isnan(missing.theta[7]) && std::isnan(missing.deflection_x[7]) && std::isnan(missing.deflection_y[7]));
  EXPECT_FLOAT_EQ(missing.deflection_x[6], 0.3f) << "its neighbours were measured";
  EXPECT_FLOAT_EQ(cycles[0].samples[101].deflection_x[7], 0.3f);
}

TEST(CycleAssembler, GapAcrossCycleBoundarySplitsLostSamplesBetweenCycles) {
  CycleAssembler a;
  PerWhisker<bool> contact{};
  std::vector<WhiskCycle> cycles;
  for (int64_t seq = 0; seq <= 1000; ++seq) {
    if (seq >= 497 && seq < 504) continue;  // 3 lost at the end of cycle 1, 4 at the start of cycle 2
    if (auto c = a.push(make_sample(seq), tag_for(seq), contact)) cycles.push_back(std::move(*c));
  }
  ASSERT_EQ(cycles.size(), 2u);
  EXPECT_EQ(cycles[0].samples.size(), 500u);
  EXPECT_EQ(cycles[0].num_missing, 3);
  EXPECT_FALSE(cycles[0].samples.back().valid);
  EXPECT_EQ(cycles[0].samples.back().phase, Phase::Retract);
  EXPECT_EQ(cycles[1].samples.size(), 500u);
  EXPECT_EQ(cycles[1].num_missing, 4);
  EXPECT_EQ(cycles[1].utime_start, kStartUtime + 500 * kPeriodUs);
  EXPECT_FALSE(cycles[1].samples.front().valid);
  EXPECT_EQ(cycles[1].samples.front().phase, Phase::Protract);
  EXPECT_TRUE(cycles[1].samples[4].valid);
}

TEST(CycleAssembler, IgnoresRepeatedOrOutOfOrderSamples) {
  CycleAssembler a;
  PerWhisker<bool> contact{};
  std::optional<WhiskCycle> done;
  for (int64_t seq = 0; seq <= 500; ++seq) {
    if (auto c = a.push(make_sample(seq), tag_for(seq), contact)) done = std::move(c);
    if (seq == 10) {
      EXPECT_FALSE(a.push(make_sample(10), tag_for(10), contact).has_value());
    }
    if (seq == 20) {
      EXPECT_FALSE(a.push(make_sample(15), tag_for(15), contact).has_value());
    }
  }
  EXPECT_EQ(a.rejected_samples(), 2);
  ASSERT_TRUE(done.has_value());
  EXPECT_EQ(done->samples.size(), 500u);
  EXPECT_EQ(done->num_missing, 0);
}

TEST(CycleAssembler, DropsAFirstCycleWhoseStartWasNotSeen) {
  CycleAssembler a;
  PerWhisker<bool> contact{};
  std::vector<WhiskCycle> cycles;
  for (int64_t seq = 200; seq <= 1000; ++seq) {
    if (auto c = a.push(make_sample(seq), tag_for(seq), contact)) cycles.push_back(std::move(*c));
  }
  ASSERT_EQ(cycles.size(), 1u);
  EXPECT_EQ(cycles[0].cycle, 2);
  EXPECT_EQ(a.discarded_cycles(), 1);
}

TEST(CycleAssembler, DiscardDropsTheCycleInProgress) {
  CycleAssembler a;
  PerWhisker<bool> contact{};
  for (int64_t seq = 0; seq < 300; ++seq) EXPECT_FALSE(a.push(make_sample(seq), tag_for(seq), contact));
  a.discard();
  EXPECT_FALSE(a.has_cycle());
  EXPECT_EQ(a.discarded_cycles(), 1);
}
