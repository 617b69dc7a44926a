// LogTimeline: a recording as a timeline, the state at any time of it equal to the live state fed
// the same messages.
#include "viewer_messages.h"

#include "whiskeye/common/channels.h"
#include "whiskeye/viewer/log_timeline.h"

#include <gtest/gtest.h>

#include <string>
#include <vector>

namespace whiskeye::viewer {
namespace {

using namespace whiskeye::viewer::test;
using nlohmann::json;

struct Logged {
  int64_t utime;
  std::string channel;
  std::vector<uint8_t> bytes;
};

// Ten seconds of a run: a pose every 20 ms, a frame every 200 ms, a whisk cycle, event, map and
// status every second.
std::vector<Logged> a_run() {
  std::vector<Logged> run;
  for (int i = 0; i < 500; ++i) {
    const int64_t t = kT0 + i * 20'000;
    run.push_back({t, channels::kVitaPose, encode_message(make_pose(0.01 * i, 0.002 * i, t))});
    if (i % 10 == 0) run.push_back({t, channels::kCamera, encode_message(make_yuyv_frame(t, 64, 48))});
    if (i % 50 == 0) {
      const int cycle = i / 50;
      run.push_back({t, channels::kWhiskCycle, encode_message(make_cycle(cycle))});
      run.push_back({t, channels::kVitaEvent,
                     encode_message(make_event(cycle % 4 == 3 ? vita_event_t::RELOCALISE : vita_event_t::NEW_EXPERIENCE,
                                               cycle, cycle - 1, cycle))});
      run.push_back({t, channels::kVitaMap, encode_message(make_map(cycle + 1, cycle, t))});
      run.push_back({t, channels::kDriverStatus,
                     encode_message(make_driver_status("camerad", driver_status_t::STATE_OK, t))});
    }
  }
  return run;
}

// The snapshot of a state fed every logged message up to t, as a live viewer would have it.
json live_snapshot(const std::vector<Logged>& run, int64_t t) {
  ViewerState s;
  for (const Logged& e : run) {
    if (e.utime <= t) s.apply(e.channel, e.utime, e.bytes);
  }
  s.set_now(t);
  json snap = s.snapshot();
  snap.erase("v");  // versions count changes, and a seek skips superseded maps and frames
  return snap;
}

json seek_snapshot(LogTimeline& timeline, int64_t t) {
  json snap = timeline.seek(t).snapshot();
  snap.erase("v");
  return snap;
}

TEST(LogTimeline, StateAtATimeIsThatOfEveryMessageUpToIt) {
  const std::vector<Logged> run = a_run();
  LogTimeline timeline;
  for (const Logged& e : run) timeline.add(e.utime, e.channel, e.bytes, nullptr);
  EXPECT_EQ(timeline.start_utime(), kT0);
  EXPECT_EQ(timeline.end_utime(), kT0 + 499 * 20'000);
  // Forward in steps, then back, then to the end: every answer is the live state at that time.
  for (const int64_t t : {kT0 - 1, kT0, kT0 + 2'345'678, kT0 + 6'000'000, kT0 + 1'000'000, kT0 + 9'980'000}) {
    EXPECT_EQ(seek_snapshot(timeline, t), live_snapshot(run, t)) << "t = " << (t - kT0) << " us";
  }
  const ViewerState& end = timeline.seek(kT0 + 9'980'000);
  EXPECT_EQ(end.num_experiences(), 10);
  EXPECT_EQ(end.snapshot()["event"]["last"]["cycle"], 9);
  EXPECT_EQ(end.messages(channels::kCamera), 50) << "skipped frames are counted";
  ASSERT_NE(end.camera_jpeg(), nullptr);
}

TEST(LogTimeline, EventsOutOfTimeOrderAreTakenByTheirTime) {
  // lcm-logger can stamp a large message after a small one logged behind it.
  LogTimeline timeline;
  const auto late = encode_message(make_event(vita_event_t::RELOCALISE, 2, 1, 0));
  const auto early = encode_message(make_event(vita_event_t::NEW_EXPERIENCE, 1, 0, 1));
  timeline.add(kT0 + 2000, channels::kVitaEvent, late, nullptr);
  timeline.add(kT0 + 1000, channels::kVitaEvent, early, nullptr);
  EXPECT_EQ(timeline.seek(kT0 + 1500).snapshot()["event"]["last"]["cycle"], 1);
  EXPECT_EQ(timeline.seek(kT0 + 2000).snapshot()["event"]["last"]["cycle"], 2);
}

TEST(LogTimeline, StatusesGoStaleAlongTheSlider) {
  LogTimeline timeline;
  const auto st = encode_message(make_driver_status("based", driver_status_t::STATE_OK, kT0));
  timeline.add(kT0, channels::kDriverStatus, st, nullptr);
  EXPECT_EQ(timeline.seek(kT0 + 1'000'000).snapshot()["status"][0]["colour"], "ok");
  EXPECT_EQ(timeline.seek(kT0 + 5'000'000).snapshot()["status"][0]["colour"], "stale");
}

}  // namespace
}  // namespace whiskeye::viewer
