// The control step allocates nothing except at the step that hands over a completed cycle.
#include <gtest/gtest.h>
#include <whiskeye/rcp/controller.h>

#include "counting_new.h"
#include "helpers.h"

using namespace whiskeye::rcp;
using whiskeye::test::allocations;
using whiskeye::rcp::test::make_sample;

TEST(ControllerAllocation, StepAllocatesOnlyWhenACycleCompletes) {
  Controller c{ControllerParams{}};
  c.enable();
  for (int64_t seq = 0; seq < 1500; ++seq) c.step(make_sample(seq, 0.003, 0.0));  // past learning
  long inside_cycle = 0;
  long at_boundary = 0;
  int completed = 0;
  for (int64_t seq = 1500; seq < 3500; ++seq) {
    WhiskerSample s = make_sample(seq, 0.003, 0.0);
    if (seq % 97 == 0) s.deflection_x[seq % 24] = -0.3;  // some contacts too
    const long before = allocations();
    const ControlOutput out = c.step(s);
    const long used = allocations() - before;
    if (out.completed_cycle) {
      ++completed;
      at_boundary += used;
    } else {
      inside_cycle += used;
    }
  }
  EXPECT_EQ(completed, 4);
  EXPECT_EQ(inside_cycle, 0);
  EXPECT_LE(at_boundary, 4 * 2);  // the next cycle's reserved storage (+ the moved-out copy)
}

TEST(ControllerAllocation, RecyclingCompletedCyclesRemovesAllAllocations) {
  Controller c{ControllerParams{}};
  c.enable();
  for (int64_t seq = 0; seq < 1500; ++seq) {
    ControlOutput out = c.step(make_sample(seq, 0.003, 0.0));
    if (out.completed_cycle) c.recycle(std::move(*out.completed_cycle));
  }
  const long before = allocations();
  int completed = 0;
  for (int64_t seq = 1500; seq < 3500; ++seq) {
    ControlOutput out = c.step(make_sample(seq, 0.003, 0.0));
    if (out.completed_cycle) {
      ++completed;
      EXPECT_EQ(out.completed_cycle->samples.size(), 500u);
      c.recycle(std::move(*out.completed_cycle));
    }
  }
  EXPECT_EQ(completed, 4);
  EXPECT_EQ(allocations() - before, 0);
}

// The cycle storage is reserved for the rate the controller is stepped at: at 1 kHz a 1 Hz cycle
// holds 1000 samples, and storage sized for 500 Hz would grow (allocate) in the middle of a cycle.
TEST(ControllerAllocation, StorageIsSizedForTheActualSampleRate) {
  constexpr int64_t kPeriod1kHz = 1000;
  Controller c{ControllerParams{}, 1000.0};
  c.enable();
  auto sample = [&](int64_t seq) {
    WhiskerSample s = make_sample(seq, 0.003, 0.0);
    s.utime = whiskeye::rcp::test::kStartUtime + seq * kPeriod1kHz;
    return s;
  };
  for (int64_t seq = 0; seq < 3000; ++seq) c.step(sample(seq));  // past learning, no recycling
  long inside_cycle = 0;
  int completed = 0;
  for (int64_t seq = 3000; seq < 7000; ++seq) {
    const long before = allocations();
    const ControlOutput out = c.step(sample(seq));
    const long used = allocations() - before;
    if (out.completed_cycle) {
      ++completed;
      EXPECT_EQ(out.completed_cycle->samples.size(), 1000u);
    } else {
      inside_cycle += used;
    }
  }
  EXPECT_EQ(completed, 4);
  EXPECT_EQ(inside_cycle, 0);
}

TEST(ControllerAllocation, RejectsANonPositiveSampleRate) {
  EXPECT_THROW(Controller(ControllerParams{}, 0.0), whiskeye::ParamError);
  EXPECT_THROW(Controller(ControllerParams{}, -500.0), whiskeye::ParamError);
}
