#include "whiskeye/slamd/cycle_sync.h"

#include <gtest/gtest.h>

#include <cstdlib>
#include <vector>

namespace whiskeye::slamd {
namespace {

constexpr int64_t kS = 1'000'000;

image_t frame(int64_t utime) {
  image_t f{};
  f.utime = utime;
  return f;
}
odometry_t odo(int64_t utime) {
  odometry_t o{};
  o.utime = utime;
  return o;
}
whisk_cycle_t cycle(int64_t n, int64_t end) {
  whisk_cycle_t c{};
  c.cycle = n;
  c.utime_start = end - kS;
  c.utime_end = end;
  return c;
}

// Feeds 50 Hz odometry and 5 Hz camera up to `until`.
void feed(CycleSynchroniser& s, int64_t from, int64_t until, bool camera = true) {
  for (int64_t t = from; t <= until; t += 20'000) {
    s.add_odometry(odo(t));
    if (camera && t % 200'000 == 0) s.add_camera(frame(t));
  }
}

TEST(CycleSync, WaitsUntilNoCloserFrameCanArrive) {
  CycleSynchroniser s(SyncParams{});
  feed(s, 20'000, 10 * kS);
  s.add_whisk_cycle(cycle(1, 10 * kS + 90'000));  // between frames at 10.0 and 10.2 s
  EXPECT_TRUE(s.take_ready().empty());
  feed(s, 10 * kS + 20'000, 10 * kS + 220'000);  // frame at 10.2 s: closer (0.11 s away)...
  EXPECT_TRUE(s.take_ready().empty()) << "…but a frame up to end+tolerance could still come";
  feed(s, 10 * kS + 240'000, 10 * kS + 400'000);  // 10.4 s ≥ end + 0.15 s
  const auto ready = s.take_ready();
  ASSERT_EQ(ready.size(), 1u);
  ASSERT_TRUE(ready[0].image);
  EXPECT_EQ(ready[0].image->utime, 10 * kS);  // 0.09 s away beats 0.11 s
}

TEST(CycleSync, HandsOutOdometryOncePerCycleInOrder) {
  CycleSynchroniser s(SyncParams{});
  feed(s, 20'000, 3 * kS);
  s.add_whisk_cycle(cycle(1, kS));
  s.add_whisk_cycle(cycle(2, 2 * kS));
  const auto ready = s.take_ready();
  ASSERT_EQ(ready.size(), 2u);
  EXPECT_EQ(ready[0].odometry.size(), 50u);  // 0.02 .. 1.00 s
  EXPECT_EQ(ready[0].odometry.back().utime, kS);
  EXPECT_EQ(ready[1].odometry.size(), 50u);  // 1.02 .. 2.00 s
  EXPECT_EQ(ready[1].odometry.front().utime, kS + 20'000);
}

TEST(CycleSync, MissingCameraDegradesAfterMaxWaitAndIsCounted) {
  CycleSynchroniser s(SyncParams{});
  feed(s, 20'000, kS + 900'000, /*camera=*/false);
  s.add_whisk_cycle(cycle(1, kS));
  EXPECT_TRUE(s.take_ready().empty()) << "data time 1.9 s < end + max_wait = 2.0 s";
  feed(s, kS + 920'000, 2 * kS, /*camera=*/false);
  const auto ready = s.take_ready();
  ASSERT_EQ(ready.size(), 1u);
  EXPECT_FALSE(ready[0].image);
  EXPECT_EQ(s.counters().cycles_without_camera, 1);
}

TEST(CycleSync, FrameOutsideToleranceIsNotUsed) {
  CycleSynchroniser s(SyncParams{});
  s.add_camera(frame(kS - 500'000));
  feed(s, 20'000, 3 * kS, false);
  s.add_whisk_cycle(cycle(1, kS));
  const auto ready = s.take_ready();
  ASSERT_EQ(ready.size(), 1u);
  EXPECT_FALSE(ready[0].image);
}

TEST(CycleSync, DropsOutOfOrderMessages) {
  CycleSynchroniser s(SyncParams{});
  feed(s, 20'000, 3 * kS);
  s.add_whisk_cycle(cycle(1, 2 * kS));
  s.add_whisk_cycle(cycle(0, kS));  // older than a pending cycle
  s.add_odometry(odo(kS));          // older than the newest odometry
  EXPECT_EQ(s.counters().out_of_order, 2);
  EXPECT_EQ(s.take_ready().size(), 1u);
}

TEST(CycleSync, DroppedMessagesSayWhy) {
  CycleSynchroniser s(SyncParams{});
  feed(s, 20'000, 3 * kS);
  EXPECT_EQ(s.add_whisk_cycle(cycle(1, 2 * kS)), "");
  const std::string why = s.add_odometry(odo(kS));
  EXPECT_NE(why.find("ODOMETRY: sample time 2.000 s before the newest"), std::string::npos) << why;
}

TEST(CycleSync, OneSampleTimeFarAheadIsDroppedAndStallsNothing) {
  // An odometry sample an hour ahead used to become data time: every pending cycle was handed out
  // at once without its camera, and every later odometry sample was dropped as out of order.
  CycleSynchroniser s(SyncParams{});
  feed(s, 20'000, kS + 100'000);
  s.add_whisk_cycle(cycle(1, kS));
  const std::string why = s.add_odometry(odo(3600 * kS));
  EXPECT_NE(why.find("ODOMETRY: sample time 3598.900 s past the other inputs"), std::string::npos) << why;
  EXPECT_TRUE(s.take_ready().empty()) << "still waiting for a frame at 1.15 s";
  feed(s, kS + 120'000, 3 * kS);
  s.add_whisk_cycle(cycle(2, 2 * kS));
  const auto ready = s.take_ready();
  ASSERT_EQ(ready.size(), 2u);
  EXPECT_TRUE(ready[0].image && ready[1].image);
  EXPECT_EQ(ready[1].odometry.size(), 50u);
  EXPECT_EQ(s.counters().time_jumps, 1);
  EXPECT_EQ(s.counters().cycles_without_camera, 0);
  // A whisk cycle ending at INT64_MAX cannot overflow the waiting arithmetic either.
  EXPECT_NE(s.add_whisk_cycle(cycle(3, INT64_MAX)), "");
}

TEST(CycleSync, AJumpTwoInputsAgreeOnIsFollowed) {
  // A clock step forward, or a new recording played after the first: every input jumps.
  CycleSynchroniser s(SyncParams{});
  feed(s, 20'000, 2 * kS);
  const int64_t later = 3600 * kS;
  EXPECT_NE(s.add_odometry(odo(later)), "");
  EXPECT_EQ(s.add_camera(frame(later + 10'000)), "") << "a second input confirms it";
  EXPECT_EQ(s.add_odometry(odo(later + 20'000)), "");
  EXPECT_EQ(s.counters().jumps_followed, 1);
  feed(s, later + 40'000, later + 3 * kS);
  s.add_whisk_cycle(cycle(9, later + kS));
  const auto ready = s.take_ready();
  ASSERT_EQ(ready.size(), 1u);
  EXPECT_TRUE(ready[0].image);
}

TEST(CycleSync, OneInputAloneGoesOnAfterAPause) {
  // Only whiskerd running (no camera, no base): whisking paused for 20 s. Its next cycles are 20 s
  // past data time and no other input can confirm the jump; they used to be dropped forever.
  CycleSynchroniser s(SyncParams{});
  for (int n = 1; n <= 5; ++n) EXPECT_EQ(s.add_whisk_cycle(cycle(n, n * kS)), "");
  EXPECT_EQ(s.take_ready().size(), 4u);  // data time 5 s: cycles 1-4 waited their max_wait
  EXPECT_NE(s.add_whisk_cycle(cycle(6, 25 * kS)), "");
  EXPECT_NE(s.add_whisk_cycle(cycle(7, 26 * kS)), "");
  EXPECT_EQ(s.add_whisk_cycle(cycle(8, 27 * kS)), "") << "the third sample in a row confirms the jump";
  EXPECT_EQ(s.add_whisk_cycle(cycle(9, 28 * kS)), "");
  EXPECT_EQ(s.counters().time_jumps, 2);
  EXPECT_EQ(s.counters().jumps_followed, 1);
  const auto ready = s.take_ready();
  ASSERT_EQ(ready.size(), 2u);
  EXPECT_EQ(ready[0].whisk.cycle, 5);
  EXPECT_EQ(ready[1].whisk.cycle, 8);
}

TEST(CycleSync, AClockSteppedBackIsFollowed) {
  // NTP stepping the robot's clock back an hour: every input goes back together. Every message used
  // to be dropped as out of order until the clock had caught up: an hour of nothing mapped.
  CycleSynchroniser s(SyncParams{});
  const int64_t before = 3600 * kS;
  feed(s, before + 20'000, before + 2 * kS);
  EXPECT_EQ(s.add_whisk_cycle(cycle(1, before + kS)), "");
  EXPECT_EQ(s.add_whisk_cycle(cycle(2, before + 2 * kS)), "");
  ASSERT_EQ(s.take_ready().size(), 1u) << "cycle 1 is complete; cycle 2 waits for a frame at +2.15 s";
  const std::string why = s.add_odometry(odo(20'000));
  EXPECT_NE(why.find("ODOMETRY: sample time 3601.980 s before the other inputs (a clock stepped back?"),
            std::string::npos)
      << why;
  EXPECT_EQ(s.add_camera(frame(40'000)), "") << "a second input confirms the step";
  EXPECT_EQ(s.counters().jumps_followed, 1);
  EXPECT_EQ(s.counters().time_jumps, 1);
  const auto handed = s.take_ready();
  ASSERT_EQ(handed.size(), 1u) << "the pending cycle is handed out as complete as it was";
  EXPECT_EQ(handed[0].whisk.cycle, 2);
  EXPECT_TRUE(handed[0].image);
  // The new time line runs as the old one did.
  feed(s, 60'000, 3 * kS);
  EXPECT_EQ(s.add_whisk_cycle(cycle(3, 2 * kS)), "");
  const auto ready = s.take_ready();
  ASSERT_EQ(ready.size(), 1u);
  EXPECT_EQ(ready[0].whisk.cycle, 3);
  EXPECT_TRUE(ready[0].image);
  EXPECT_EQ(ready[0].image->utime, 2 * kS);
  ASSERT_FALSE(ready[0].odometry.empty());
  EXPECT_EQ(ready[0].odometry.front().utime, 60'000);
  EXPECT_EQ(ready[0].odometry.back().utime, 2 * kS);
  EXPECT_EQ(s.counters().out_of_order, 0);
  // A late message of a few seconds is still just out of order.
  EXPECT_NE(s.add_odometry(odo(kS)).find("out of order"), std::string::npos);
}

TEST(CycleSync, OneInputAloneFollowsItsClockSteppedBackOnlyWhileTheOthersAreSilent) {
  // Only whiskerd running: its clock goes back; three cycles over 2 s confirm it.
  CycleSynchroniser s(SyncParams{});
  const int64_t before = 3600 * kS;
  for (int n = 1; n <= 3; ++n) EXPECT_EQ(s.add_whisk_cycle(cycle(n, before + n * kS)), "");
  EXPECT_NE(s.add_whisk_cycle(cycle(4, kS)), "");
  EXPECT_NE(s.add_whisk_cycle(cycle(5, 2 * kS)), "");
  EXPECT_EQ(s.add_whisk_cycle(cycle(6, 3 * kS)), "");
  EXPECT_EQ(s.counters().jumps_followed, 1);
  // The base alone with a clock an hour behind the camera and whiskerd, which are still running:
  // its samples never take data time from them, however many come in a row.
  CycleSynchroniser t(SyncParams{});
  feed(t, before + 20'000, before + 2 * kS);
  for (int i = 1; i <= 200; ++i) {
    EXPECT_NE(t.add_odometry(odo(i * 20'000)), "") << i;
    if (i % 10 == 0) {
      EXPECT_EQ(t.add_camera(frame(before + 2 * kS + i * 20'000)), "") << i;
    }
  }
  EXPECT_EQ(t.counters().jumps_followed, 0);
  EXPECT_EQ(t.data_time(), before + 6 * kS);
  // Nor, ahead, one input with a clock an hour fast while another is running (it used to win after
  // three samples, and every sample of the others was then dropped as out of order).
  CycleSynchroniser u(SyncParams{});
  feed(u, 20'000, 2 * kS);
  for (int i = 1; i <= 200; ++i) {
    EXPECT_NE(u.add_odometry(odo(before + i * 20'000)), "") << i;
    if (i % 10 == 0) {
      EXPECT_EQ(u.add_camera(frame(2 * kS + i * 20'000)), "") << i;
    }
  }
  EXPECT_EQ(u.counters().jumps_followed, 0);
}

TEST(CycleSync, BadTimesBetweenGoodOnesAreNeverFollowed) {
  // A sender stamping every other sample an hour ahead: each bad time starts over, none confirms.
  CycleSynchroniser s(SyncParams{});
  feed(s, 20'000, 2 * kS);
  for (int i = 1; i <= 10; ++i) {
    EXPECT_NE(s.add_odometry(odo(3600 * kS + i * 20'000)), "") << i;
    EXPECT_EQ(s.add_odometry(odo(2 * kS + i * 20'000)), "") << i;
  }
  EXPECT_EQ(s.counters().time_jumps, 10);
  EXPECT_EQ(s.counters().jumps_followed, 0);
  EXPECT_EQ(s.data_time(), 2 * kS + 200'000);
}

TEST(CycleSync, ACorruptFirstSampleIsUndone) {
  // The very first odometry sample an hour ahead: nothing could check it, it became data time, and
  // every later odometry sample was "out of order" for an hour (cycles handed out at once, without
  // their frame and their motion).
  CycleSynchroniser s(SyncParams{});
  EXPECT_EQ(s.add_odometry(odo(3600 * kS)), "");
  EXPECT_EQ(s.add_camera(frame(200'000)), "");
  EXPECT_NE(s.add_odometry(odo(220'000)), "");
  EXPECT_NE(s.add_odometry(odo(240'000)), "");
  EXPECT_EQ(s.add_odometry(odo(260'000)), "") << "three samples in a row agree with the camera";
  EXPECT_EQ(s.counters().outliers_dropped, 1);
  EXPECT_EQ(s.data_time(), 260'000);
  feed(s, 280'000, 2 * kS);
  s.add_whisk_cycle(cycle(1, kS));
  const auto ready = s.take_ready();
  ASSERT_EQ(ready.size(), 1u);
  EXPECT_TRUE(ready[0].image);
  ASSERT_FALSE(ready[0].odometry.empty());
  EXPECT_EQ(ready[0].odometry.front().utime, 260'000) << "the corrupt sample is gone";
  EXPECT_EQ(ready[0].odometry.back().utime, kS);
  // A whisk cycle's corrupt first time is undone the same way.
  CycleSynchroniser w(SyncParams{});
  EXPECT_EQ(w.add_whisk_cycle(cycle(1, 3600 * kS)), "");
  feed(w, 20'000, 5 * kS);
  EXPECT_NE(w.add_whisk_cycle(cycle(2, 2 * kS)), "");
  EXPECT_NE(w.add_whisk_cycle(cycle(3, 3 * kS)), "");
  EXPECT_EQ(w.add_whisk_cycle(cycle(4, 4 * kS)), "");
  const auto cycles = w.take_ready();
  ASSERT_EQ(cycles.size(), 1u);
  EXPECT_EQ(cycles[0].whisk.cycle, 4);
  EXPECT_TRUE(cycles[0].image);
}

TEST(CycleSync, OdometryWithoutWhiskCyclesIsBounded) {
  // Whisking stopped while the base drives: nothing consumes odometry, and it used to pile up
  // (~15 MB an hour at 50 Hz, forever).
  SyncParams p;
  p.odometry_buffer = 100;
  CycleSynchroniser s(p);
  feed(s, 20'000, 3 * kS, /*camera=*/false);  // 150 samples
  EXPECT_EQ(s.counters().odometry_overflow, 50);
  s.add_whisk_cycle(cycle(1, 3 * kS));
  const auto ready = s.flush();
  ASSERT_EQ(ready.size(), 1u);
  ASSERT_EQ(ready[0].odometry.size(), 100u) << "the newest 100";
  EXPECT_EQ(ready[0].odometry.front().utime, kS + 20'000);
}

// A camera at `fps` with no odometry (the base down) from `from` to `until`, a whisk cycle ending every
// second in between (each arriving at its end, as whiskerd sends it); the cycles handed out.
std::vector<SyncedCycle> camera_without_odometry(CycleSynchroniser& s, double fps, int64_t from, int64_t until) {
  std::vector<SyncedCycle> out;
  const auto period = static_cast<int64_t>(1e6 / fps);
  int64_t next_cycle = from + kS;
  int n = 0;
  for (int64_t t = from; t <= until; t += period) {
    if (t >= next_cycle) {
      s.add_whisk_cycle(cycle(++n, next_cycle));
      next_cycle += kS;
    }
    s.add_camera(frame(t));
    for (auto& c : s.take_ready()) out.push_back(std::move(c));
  }
  return out;
}

TEST(CycleSync, WithoutOdometryEveryCycleKeepsItsFrameAtThirtyFps) {
  // A cycle missing its odometry waits max_wait_s (1 s) of data time; a 30 fps camera sends ~35
  // frames meanwhile, and a buffer of the last 16 had dropped the one near the cycle's end.
  CycleSynchroniser s(SyncParams{});
  const auto cycles = camera_without_odometry(s, 30.0, 10 * kS, 40 * kS);
  ASSERT_GE(cycles.size(), 25u);
  for (const auto& c : cycles) {
    ASSERT_TRUE(c.image) << "cycle " << c.whisk.cycle;
    EXPECT_LE(std::llabs(c.image->utime - c.whisk.utime_end), 34'000) << "cycle " << c.whisk.cycle;
  }
  EXPECT_EQ(s.counters().cycles_without_camera, 0);
  EXPECT_EQ(s.counters().camera_overflow, 0);
}

TEST(CycleSync, ABufferTooSmallForTheCameraRateCountsWhatItDrops) {
  SyncParams p;
  p.camera_buffer = 8;
  CycleSynchroniser s(p);
  const auto cycles = camera_without_odometry(s, 30.0, 10 * kS, 20 * kS);
  ASSERT_GE(cycles.size(), 8u);
  EXPECT_GT(s.counters().camera_overflow, 0);
  EXPECT_GT(s.counters().cycles_without_camera, 0) << "8 frames at 30 fps: 0.27 s, the cycles waited 1 s";
  EXPECT_LE(s.buffered_frames(), 8u);
}

TEST(CycleSync, FramesAreKeptForATimeNotACount) {
  // 30 fps with odometry: the camera's last camera_buffer_s (3 s), whatever the rate, and no more.
  CycleSynchroniser s(SyncParams{});
  for (int64_t t = 20'000; t <= 30 * kS; t += 20'000) {
    s.add_odometry(odo(t));
    if (t % 100'000 == 0) {
      for (int64_t f = t - 100'000 + 33'334; f <= t; f += 33'333) s.add_camera(frame(f));
    }
  }
  EXPECT_GE(s.buffered_frames(), 89u);
  EXPECT_LE(s.buffered_frames(), 91u);
  EXPECT_EQ(s.counters().camera_overflow, 0);
  // A whisk cycle whose message comes 2.5 s late (whiskerd stalled) still finds its frame.
  s.add_whisk_cycle(cycle(1, 27 * kS + 500'000));
  const auto ready = s.take_ready();
  ASSERT_EQ(ready.size(), 1u);
  ASSERT_TRUE(ready[0].image);
  EXPECT_LE(std::llabs(ready[0].image->utime - (27 * kS + 500'000)), 17'000);
}

TEST(CycleSync, AWaitingCycleKeepsItsFramesWhenDataTimeLeapsPastIt) {
  // The cycle at 5 s waits for odometry; the camera pauses, then its next frame is 4 s later: that
  // frame releases the cycle, which still gets the frame at its end (4 s old, beyond camera_buffer_s).
  CycleSynchroniser s(SyncParams{});
  feed(s, 20'000, 4 * kS);
  for (int64_t t = 4 * kS + 200'000; t <= 5 * kS + 200'000; t += 200'000) s.add_camera(frame(t));
  s.add_whisk_cycle(cycle(1, 5 * kS));
  EXPECT_TRUE(s.take_ready().empty()) << "odometry stopped at 4 s";
  s.add_camera(frame(9 * kS));
  const auto ready = s.take_ready();
  ASSERT_EQ(ready.size(), 1u);
  ASSERT_TRUE(ready[0].image);
  EXPECT_EQ(ready[0].image->utime, 5 * kS);
}

TEST(CycleSync, FlushHandsOutEverythingPending) {
  CycleSynchroniser s(SyncParams{});
  feed(s, 20'000, kS);
  s.add_whisk_cycle(cycle(1, kS));
  EXPECT_TRUE(s.take_ready().empty());  // camera at 1.0 s, not yet 1.15 s
  const auto rest = s.flush();
  ASSERT_EQ(rest.size(), 1u);
  ASSERT_TRUE(rest[0].image);
  EXPECT_EQ(rest[0].image->utime, kS);
}

}  // namespace
}  // namespace whiskeye::slamd
