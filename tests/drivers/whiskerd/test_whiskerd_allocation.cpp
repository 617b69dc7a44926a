// whiskerd's real-time path allocates nothing in steady state: a WhiskerCore stepped through many
// whisk cycles, with every completed cycle handed back (as the publisher thread does) and a stream
// of rejected CAN frames, at 500 Hz and at 1 kHz. Its own binary: it replaces the global operator new.
#include <gtest/gtest.h>

#include <memory>
#include <utility>

#include "counting_new.h"
#include "whiskeye/whiskerd/whiskerd_core.h"
#include "whiskerd_rig.h"

using namespace whiskeye;
using whiskeye::test::allocations;
using namespace whiskeye::whiskerd;
using namespace whiskeye::whiskerd::test;

namespace {

// One control period as ControlLoop (src/control_loop.cpp) runs it: cycles handed back first, frames (good ones and
// a burst of rejected ones), then step(); the published cycle is handed back as the publisher does.
struct RtLoop {
  explicit RtLoop(const Params& p) : rig(p) {}
  void period() {
    if (returned) rig.core.recycle(std::move(returned));
    std::array<uint8_t, 32> junk{};
    rig.core.on_frame(0x555, true, junk, rig.mono);                                 // unknown id
    rig.core.on_frame(wp::sample_id({}, 0), true, std::span(junk.data(), 24), rig.mono);  // wrong length
    rig.core.on_frame(wp::sample_id({}, 1), false, std::span(junk.data(), 8), rig.mono);  // classic on FD
    rig.run(1);
    if (rig.out.completed_cycle) {
      ++cycles;
      last_cycle_samples = rig.out.completed_cycle->samples.size();
      returned = std::move(rig.out.completed_cycle);  // "published", back on the next period
    }
  }
  Rig rig;
  std::unique_ptr<rcp::WhiskCycle> returned;
  int cycles = 0;
  std::size_t last_cycle_samples = 0;
};

void expect_no_allocation_in_steady_state(double rate_hz) {
  Params p = test_params();
  p.rate_hz = rate_hz;
  RtLoop loop(p);
  const int per_cycle = static_cast<int>(rate_hz / p.controller.pattern.frequency_hz);
  for (int i = 0; i < 3 * per_cycle; ++i) loop.period();  // warm-up: start, first cycles
  ASSERT_EQ(loop.rig.core.safety(), Safety::kRunning);
  ASSERT_GE(loop.cycles, 1);

  const int cycles_before = loop.cycles;
  const long before = allocations();
  for (int i = 0; i < 4 * per_cycle; ++i) loop.period();
  const long used = allocations() - before;
  EXPECT_EQ(loop.cycles - cycles_before, 4);
  EXPECT_EQ(loop.last_cycle_samples, static_cast<std::size_t>(per_cycle));
  EXPECT_GE(loop.rig.core.counters()[Counters::kRejectedUnknownId], 7 * per_cycle);
  EXPECT_GE(loop.rig.core.counters()[Counters::kRejectedWrongLength], 7 * per_cycle);
  EXPECT_GE(loop.rig.core.counters()[Counters::kRejectedWrongFrameType], 7 * per_cycle);
  EXPECT_EQ(used, 0) << "allocations over 4 whisk cycles at " << rate_hz << " Hz";
}

}  // namespace

TEST(WhiskerdAllocation, SteadyStateAt500HzAllocatesNothing) { expect_no_allocation_in_steady_state(500.0); }

TEST(WhiskerdAllocation, SteadyStateAt1kHzAllocatesNothing) { expect_no_allocation_in_steady_state(1000.0); }

TEST(WhiskerdAllocation, RejectedFramesAllocateNothing) {
  Rig rig;
  std::array<uint8_t, 64> junk{};
  const long before = allocations();
  for (int i = 0; i < 100; ++i) {
    rig.core.on_frame(0x555 + i % 3, true, junk, rig.mono);
    rig.core.on_frame(wp::sample_id({}, i % 6), true, std::span(junk.data(), 5 + i % 20), rig.mono);
  }
  EXPECT_EQ(allocations() - before, 0);
  EXPECT_EQ(rig.core.counters()[Counters::kRejectedUnknownId] + rig.core.counters()[Counters::kRejectedWrongLength], 200);
}

// A cycle that is never handed back (the publisher ring was full) is reused at the next period, and
// a recycled cycle never carries samples of the one before.
TEST(WhiskerdAllocation, RecycledCyclesCarryOnlyTheirOwnSamples) {
  Rig rig;
  int cycles = 0;
  int64_t last_end = 0;
  for (int i = 0; i < 6000; ++i) {
    rig.run(1);
    if (const auto& c = rig.out.completed_cycle) {
      ++cycles;
      ASSERT_FALSE(c->samples.empty());
      EXPECT_EQ(c->utime_start, c->samples.front().utime);
      EXPECT_EQ(c->utime_end, c->samples.back().utime);
      EXPECT_GT(c->utime_start, last_end);
      last_end = c->utime_end;
      if (cycles > 1) {
        EXPECT_EQ(c->samples.size(), 500u);
      }
      // Every other cycle is handed back; the rest stay in `out` and the core reclaims them.
      if (cycles % 2 == 0) rig.core.recycle(std::move(rig.out.completed_cycle));
    }
  }
  EXPECT_GE(cycles, 10);
}

// The counter is live in this binary (otherwise every "0 allocations" above would prove nothing).
TEST(WhiskerdAllocation, CounterSeesAnAllocation) {
  const long before = allocations();
  auto p = std::make_unique<rcp::WhiskCycle>();
  EXPECT_GT(allocations(), before);
}
