// whiskeye-viewer's pure parts: the aggregated state and its JSON, a log as a timeline, the clients'
// bounded queues, and the embedded page files.
#include "whiskeye/common/bus.h"
#include "whiskeye/common/channels.h"
#include "whiskeye/viewer/assets.h"
#include "whiskeye/viewer/client_hub.h"
#include "whiskeye/viewer/log_timeline.h"
#include "whiskeye/viewer/viewer_state.h"

#include <whiskeye/image_t.hpp>

#include <gtest/gtest.h>
#include <opencv2/imgcodecs.hpp>

#include <cmath>
#include <limits>

namespace whiskeye::viewer {
namespace {

using nlohmann::json;
constexpr int64_t kT0 = 1'700'000'000'000'000;  // an epoch time, µs

vita_map_t make_map(int n, int current, int64_t utime = kT0) {
  vita_map_t m{};
  m.utime = utime;
  m.mode = vita_pose_t::MODE_VITA;
  m.current_experience_id = current;
  for (int i = 0; i < n; ++i) {
    experience_t e{};
    e.id = i;
    e.x = 0.5 * i;
    e.y = -0.25 * i;
    e.visual_template_id = i;
    e.tactile_template_id = i % 3 == 0 ? i : -1;
    e.dense = i % 3 == 0;
    m.experiences.push_back(e);
    if (i > 0) {
      link_t l{};
      l.from_id = i - 1;
      l.to_id = i;
      m.links.push_back(l);
    }
  }
  m.num_experiences = n;
  m.num_links = static_cast<int32_t>(m.links.size());
  return m;
}

vita_pose_t make_pose(double x, double y, int64_t utime = kT0) {
  vita_pose_t p{};
  p.utime = utime;
  p.x = x;
  p.y = y;
  p.theta = 0.5;
  p.experience_id = 3;
  p.template_id = 4;
  p.mode = vita_pose_t::MODE_VITA;
  return p;
}

vita_event_t make_event(int8_t type, int64_t cycle, int from, int to) {
  vita_event_t e{};
  e.utime = kT0 + cycle * 1'000'000;
  e.cycle = cycle;
  e.type = type;
  e.from_id = from;
  e.to_id = to;
  e.template_id = 7;
  e.mode = vita_pose_t::MODE_VITA;
  return e;
}

driver_status_t make_driver_status(const std::string& name, int8_t state, int64_t utime) {
  driver_status_t s{};
  s.utime = utime;
  s.driver = name;
  s.state = state;
  s.message = state == driver_status_t::STATE_OK ? "" : "camera unplugged";
  s.counter_names = {"frames", "errors"};
  s.counter_values = {120, 2};
  s.num_counters = 2;
  s.stat_names = {"rate_hz"};
  s.stat_values = {5.0};
  s.num_stats = 1;
  return s;
}

// A whisk cycle of `samples` samples; whisker 5 touches from sample 10 on with deflection 0.6,
// whisker 7 is not measured (NaN), the others deflect 0.1.
whisk_cycle_t make_cycle(int64_t cycle, int samples = 50) {
  whisk_cycle_t c{};
  c.cycle = cycle;
  c.utime_start = kT0 + cycle * 1'000'000;
  c.utime_end = c.utime_start + (samples - 1) * 2000;
  c.utime = c.utime_end;
  c.num_whiskers = 24;
  c.num_samples = samples;
  c.num_missing = 0;
  const float nan = std::numeric_limits<float>::quiet_NaN();
  for (int s = 0; s < samples; ++s) {
    c.sample_utime.push_back(c.utime_start + s * 2000);
    c.sample_valid.push_back(1);
    c.phase.push_back(0);
    std::vector<float> theta(24, 0.3f + 0.001f * static_cast<float>(s)), dx(24, 0.1f), dy(24, 0.0f);
    std::vector<int8_t> contact(24, 0);
    if (s >= 10) {
      dx[5] = 0.6f;
      contact[5] = 1;
    }
    theta[7] = dx[7] = dy[7] = nan;
    c.theta.push_back(theta);
    c.deflection_x.push_back(dx);
    c.deflection_y.push_back(dy);
    c.contact.push_back(contact);
  }
  return c;
}

image_t make_yuyv_frame(int64_t utime, int width = 640, int height = 480) {
  image_t im{};
  im.utime = utime;
  im.seq = 1;
  im.width = width;
  im.height = height;
  im.row_stride = width * 2;
  im.pixelformat = image_t::PIXEL_FORMAT_YUYV;
  im.data.assign(static_cast<std::size_t>(im.row_stride * height), 128);
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < width; ++x) im.data[static_cast<std::size_t>(y * im.row_stride + 2 * x)] = static_cast<uint8_t>(x % 256);
  }
  im.size = static_cast<int32_t>(im.data.size());
  return im;
}

template <typename T>
bool feed(ViewerState& s, const char* channel, const T& msg, int64_t recv = kT0) {
  const std::vector<uint8_t> bytes = encode_message(msg);
  return s.apply(channel, recv, bytes);
}

TEST(ViewerState, CountsExperiencesDenseAndSparseAndTheCurrentOne) {
  ViewerState s;
  ASSERT_TRUE(feed(s, channels::kVitaMap, make_map(10, 6)));
  const json map = s.snapshot()["map"];
  EXPECT_EQ(map["num_experiences"], 10);
  EXPECT_EQ(map["num_dense"], 4);  // ids 0, 3, 6, 9
  EXPECT_EQ(map["num_sparse"], 6);
  EXPECT_EQ(map["current"], 6);
  EXPECT_EQ(map["mode"], "vita");
  EXPECT_EQ(map["id"].size(), 10u);
  EXPECT_EQ(map["x"][4], 2.0);
  EXPECT_EQ(map["y"][4], -1.0);
  EXPECT_EQ(map["dense"][3], 1);
  EXPECT_EQ(map["dense"][4], 0);
  EXPECT_EQ(s.num_experiences(), 10);
  EXPECT_EQ(s.current_experience(), 6);
  // A newer map replaces the whole of the old one.
  ASSERT_TRUE(feed(s, channels::kVitaMap, make_map(3, 1)));
  EXPECT_EQ(s.snapshot()["map"]["num_experiences"], 3);
  EXPECT_EQ(s.snapshot()["map"]["current"], 1);
}

TEST(ViewerState, LinksAreSentAsPairsOfExperienceIds) {
  ViewerState s;
  vita_map_t m = make_map(4, 0);
  link_t closure{};
  closure.from_id = 3;
  closure.to_id = 0;  // a loop closure back to the first experience
  m.links.push_back(closure);
  m.num_links = static_cast<int32_t>(m.links.size());
  ASSERT_TRUE(feed(s, channels::kVitaMap, m));
  const json map = s.snapshot()["map"];
  EXPECT_EQ(map["num_links"], 4);
  EXPECT_EQ(map["links"], json({0, 1, 1, 2, 2, 3, 3, 0}));
}

TEST(ViewerState, NothingReceivedShowsEmptySections) {
  const json snap = ViewerState().snapshot();
  EXPECT_TRUE(snap["map"].is_null());
  EXPECT_TRUE(snap["pose"].is_null());
  EXPECT_TRUE(snap["camera"].is_null());
  EXPECT_TRUE(snap["event"]["last"].is_null());
  EXPECT_EQ(snap["event"]["counts"]["new"], 0);
  EXPECT_TRUE(snap["status"].empty());
  EXPECT_EQ(snap["trail"]["xy"].size(), 0u);
}

TEST(ViewerState, LastEventCarriesItsFieldsAndEachKindIsCounted) {
  ViewerState s;
  ASSERT_TRUE(feed(s, channels::kVitaEvent, make_event(vita_event_t::NEW_EXPERIENCE, 1, -1, 0)));
  ASSERT_TRUE(feed(s, channels::kVitaEvent, make_event(vita_event_t::NEW_EXPERIENCE, 2, 0, 1)));
  ASSERT_TRUE(feed(s, channels::kVitaEvent, make_event(vita_event_t::SAME_EXPERIENCE, 3, 1, 1)));
  ASSERT_TRUE(feed(s, channels::kVitaEvent, make_event(vita_event_t::RELOCALISE, 4, 1, 0)));
  const json ev = s.snapshot()["event"];
  EXPECT_EQ(ev["last"]["type"], "relocalise");
  EXPECT_EQ(ev["last"]["cycle"], 4);
  EXPECT_EQ(ev["last"]["from_id"], 1);
  EXPECT_EQ(ev["last"]["to_id"], 0);
  EXPECT_EQ(ev["last"]["template_id"], 7);
  EXPECT_EQ(ev["counts"], json({{"same", 1}, {"new", 2}, {"relocalise", 1}}));
}

TEST(ViewerState, MatchCarriesEpsilonAndItsTerms) {
  ViewerState s;
  template_match_t m{};
  m.utime = kT0;
  m.cycle = 9;
  m.template_id = 4;
  m.is_new = false;
  m.error = 0.75;
  m.visual_error = 0.5;
  m.pfh_error = 0.125;
  m.sda_error = 0.125;
  m.visual_shift = -2;
  m.num_templates = 12;
  m.mode = vita_pose_t::MODE_VITA;
  m.visual_used = true;
  m.tactile_used = false;
  ASSERT_TRUE(feed(s, channels::kVitaMatch, m));
  const json j = s.snapshot()["match"];
  EXPECT_EQ(j["error"], 0.75);
  EXPECT_EQ(j["visual_error"], 0.5);
  EXPECT_EQ(j["pfh_error"], 0.125);
  EXPECT_EQ(j["sda_error"], 0.125);
  EXPECT_EQ(j["is_new"], false);
  EXPECT_EQ(j["visual_shift"], -2);
  EXPECT_EQ(j["num_templates"], 12);
  EXPECT_EQ(j["tactile_used"], false);
  // A new template's ε may be infinite (nothing stored yet): not a JSON number, so null.
  m.error = std::numeric_limits<double>::infinity();
  ASSERT_TRUE(feed(s, channels::kVitaMatch, m));
  EXPECT_TRUE(s.snapshot()["match"]["error"].is_null());
  EXPECT_NO_THROW(s.snapshot().dump());
}

TEST(ViewerState, StatusColourFollowsTheStateAndTurnsStaleWhenADaemonFallsSilent) {
  ViewerState s;
  ASSERT_TRUE(feed(s, channels::kDriverStatus, make_driver_status("camerad", driver_status_t::STATE_DEGRADED, kT0), kT0));
  ASSERT_TRUE(feed(s, channels::kDriverStatus, make_driver_status("based", driver_status_t::STATE_OK, kT0), kT0));
  slam_status_t slam{};
  slam.utime = kT0;
  slam.state = driver_status_t::STATE_FAULT;
  slam.cycles = 42;
  slam.num_experiences = 7;
  slam.lcm_receive_drops = 3;
  slam.input_gaps = 4;
  ASSERT_TRUE(feed(s, channels::kSlamStatus, slam, kT0));
  json status = s.snapshot()["status"];
  ASSERT_EQ(status.size(), 3u);  // by name: based, camerad, slamd
  EXPECT_EQ(status[0]["name"], "based");
  EXPECT_EQ(status[0]["colour"], "ok");
  EXPECT_EQ(status[1]["name"], "camerad");
  EXPECT_EQ(status[1]["colour"], "degraded");
  EXPECT_EQ(status[1]["message"], "camera unplugged");
  EXPECT_EQ(status[1]["counters"], json::array({json::array({"frames", 120.0}), json::array({"errors", 2.0})}));
  EXPECT_EQ(status[1]["stats"][0][0], "rate_hz");
  EXPECT_EQ(status[2]["name"], "slamd");
  EXPECT_EQ(status[2]["kind"], "slam");
  EXPECT_EQ(status[2]["colour"], "fault");
  EXPECT_EQ(status[2]["counters"][0], json({"cycles", 42.0}));
  EXPECT_EQ(status[2]["counters"][2], json({"experiences", 7.0}));
  const json& slam_counters = status[2]["counters"];
  EXPECT_EQ(slam_counters[slam_counters.size() - 2], json({"lcm_receive_drops", 3.0}));
  EXPECT_EQ(slam_counters.back(), json({"input_gaps", 4.0}));

  // based keeps reporting, the others fall silent for more than 3 s: stale, whatever they said last.
  const ViewerState::Versions before = s.versions();
  ASSERT_TRUE(feed(s, channels::kDriverStatus, make_driver_status("based", driver_status_t::STATE_OK, kT0 + 3'500'000),
                   kT0 + 3'500'000));
  status = s.snapshot()["status"];
  EXPECT_EQ(status[0]["colour"], "ok");
  EXPECT_EQ(status[1]["colour"], "stale");
  EXPECT_EQ(status[1]["state"], "degraded");
  EXPECT_EQ(status[2]["colour"], "stale");
  EXPECT_EQ(status[2]["age_s"], 3.5);
  EXPECT_NE(s.versions()[ViewerState::kStatus], before[ViewerState::kStatus]);
  EXPECT_STREQ(state_name(driver_status_t::STATE_STARTING), "starting");
  EXPECT_STREQ(state_name(9), "unknown");
}

TEST(ViewerState, TrailIsBoundedAndSkipsStepsShorterThanTheMinimum) {
  ViewerParams p;
  p.trail_max_points = 100;
  p.trail_min_step_m = 0.05;
  ViewerState s(p);
  for (int i = 0; i < 1000; ++i) ASSERT_TRUE(feed(s, channels::kVitaPose, make_pose(0.01 * i, 0.0)));
  // 10 m in 1 cm steps: a point every 5 or 6 cm (rounding), of which the newest 100 are kept.
  EXPECT_EQ(s.trail_size(), 100u);
  const json snap = s.snapshot();
  const json& xy = snap["trail"]["xy"];
  ASSERT_EQ(xy.size(), 200u);
  EXPECT_EQ(snap["trail"]["max_points"], 100);
  EXPECT_NEAR(xy[198].get<double>(), 9.96, 0.031);  // the newest point
  for (std::size_t i = 2; i < xy.size(); i += 2) {
    EXPECT_GE(xy[i].get<double>() - xy[i - 2].get<double>(), 0.0499) << i;
  }
  EXPECT_NEAR(snap["pose"]["x"].get<double>(), 9.99, 1e-9);         // the pose is always the newest
  EXPECT_EQ(snap["pose"]["experience_id"], 3);
}

TEST(ViewerState, WhiskersShowThisCyclesContactsAndPeakDeflection) {
  ViewerState s;
  ASSERT_TRUE(feed(s, channels::kWhiskCycle, make_cycle(5)));
  const json w = s.snapshot()["whiskers"];
  EXPECT_EQ(w["cycle"], 5);
  EXPECT_EQ(w["num_samples"], 50);
  EXPECT_EQ(w["rows"], 4);
  EXPECT_EQ(w["columns"], 6);
  EXPECT_EQ(w["num_contacts"], 1);
  EXPECT_EQ(w["contact"][5], true);
  EXPECT_EQ(w["contact"][4], false);
  EXPECT_NEAR(w["deflection"][5].get<double>(), 0.6, 1e-3);
  EXPECT_NEAR(w["deflection"][4].get<double>(), 0.1, 1e-3);
  EXPECT_TRUE(w["deflection"][7].is_null()) << "whisker 7 was not measured";
  EXPECT_NEAR(w["theta_max"][0].get<double>(), 0.349, 1e-3);
}

TEST(ViewerState, MalformedMessagesAreCountedNotShown) {
  ViewerState s;
  const std::vector<uint8_t> pose = encode_message(make_pose(1, 2));
  EXPECT_FALSE(s.apply(channels::kVitaMap, kT0, pose)) << "a pose on the map channel: wrong fingerprint";
  // A whisk cycle claiming two billion samples is refused before anything is allocated for them.
  std::vector<uint8_t> cycle = encode_message(make_cycle(1));
  cycle[8 + 4 * 8 + 4] = 0x7f;
  EXPECT_FALSE(s.apply(channels::kWhiskCycle, kT0, cycle));
  // A frame whose pixels do not fill its header.
  image_t frame = make_yuyv_frame(kT0, 64, 48);
  frame.height = 480;
  EXPECT_FALSE(s.apply(channels::kCamera, kT0, encode_message(frame)));
  EXPECT_EQ(s.decode_errors(), 3);
  const json snap = s.snapshot();
  EXPECT_TRUE(snap["map"].is_null());
  EXPECT_TRUE(snap["whiskers"].is_null());
  EXPECT_TRUE(snap["camera"].is_null());
  EXPECT_EQ(snap["meta"]["decode_errors"], 3);
  EXPECT_NE(snap["meta"]["last_decode_error"].get<std::string>().find("CAMERA"), std::string::npos);
  // A channel the viewer does not show is ignored, not an error.
  EXPECT_FALSE(s.apply(channels::kWhiskerSample, kT0, pose));
  EXPECT_EQ(s.decode_errors(), 3);
}

TEST(ViewerState, DeltaHoldsOnlyWhatChangedAndTheTrailAtMostOncePerPeriod) {
  ViewerState s;
  ViewerState::Cursor cursor;
  json d = s.delta(cursor, 0);
  EXPECT_TRUE(d.contains("meta"));  // everything is new to a fresh cursor
  EXPECT_TRUE(d.contains("map"));
  EXPECT_TRUE(s.delta(cursor, 0).empty()) << "nothing changed since";

  ASSERT_TRUE(feed(s, channels::kVitaEvent, make_event(vita_event_t::NEW_EXPERIENCE, 1, -1, 0)));
  d = s.delta(cursor, 100'000);
  EXPECT_TRUE(d.contains("event"));
  EXPECT_TRUE(d.contains("meta"));
  EXPECT_FALSE(d.contains("map"));
  EXPECT_FALSE(d.contains("pose"));
  EXPECT_EQ(d["v"], s.version());

  ASSERT_TRUE(feed(s, channels::kVitaPose, make_pose(1, 0)));
  d = s.delta(cursor, 200'000);
  EXPECT_TRUE(d.contains("pose"));
  EXPECT_FALSE(d.contains("trail")) << "the trail was sent 0.2 s ago (with the first delta)";
  ASSERT_TRUE(feed(s, channels::kVitaPose, make_pose(2, 0)));
  d = s.delta(cursor, 1'000'000);
  EXPECT_TRUE(d.contains("pose"));
  EXPECT_TRUE(d.contains("trail")) << "a second after the last one";
  EXPECT_EQ(d["trail"]["xy"].size(), 4u);
}

TEST(ViewerState, CameraFrameIsShownAsASmallJpeg) {
  ViewerState s;
  EXPECT_EQ(s.camera_jpeg(), nullptr);
  ASSERT_TRUE(feed(s, channels::kCamera, make_yuyv_frame(kT0)));
  const json cam = s.snapshot()["camera"];
  EXPECT_EQ(cam["width"], 640);
  EXPECT_EQ(cam["frame"], 1);
  const auto jpeg = s.camera_jpeg();
  ASSERT_NE(jpeg, nullptr);
  const std::vector<uint8_t> bytes(jpeg->begin(), jpeg->end());
  const cv::Mat decoded = cv::imdecode(bytes, cv::IMREAD_COLOR);
  EXPECT_EQ(decoded.cols, 320);
  EXPECT_EQ(decoded.rows, 240);
  EXPECT_EQ(s.camera_jpeg(), jpeg) << "encoded once per frame";
  EXPECT_LT(jpeg->size(), 40'000u);
}

TEST(ViewerState, AGreyMjpegOrColourFrameEachConvert) {
  for (const int32_t format : std::initializer_list<int32_t>{image_t::PIXEL_FORMAT_GREY, image_t::PIXEL_FORMAT_RGB24,
                                                             image_t::PIXEL_FORMAT_BGR24}) {
    image_t im{};
    im.utime = kT0;
    im.width = 160;
    im.height = 120;
    const int bpp = format == image_t::PIXEL_FORMAT_GREY ? 1 : 3;
    im.row_stride = im.width * bpp;
    im.pixelformat = format;
    im.data.assign(static_cast<std::size_t>(im.row_stride * im.height), 90);
    im.size = static_cast<int32_t>(im.data.size());
    ViewerState s;
    ASSERT_TRUE(feed(s, channels::kCamera, im)) << format;
    ASSERT_NE(s.camera_jpeg(), nullptr) << format;
  }
  // A damaged MJPEG frame (no JPEG at all) is shown as no frame, not a crash.
  image_t bad{};
  bad.utime = kT0;
  bad.width = 64;
  bad.height = 48;
  bad.pixelformat = image_t::PIXEL_FORMAT_MJPEG;
  bad.data.assign(100, 0xab);
  bad.size = 100;
  ViewerState s;
  ASSERT_TRUE(feed(s, channels::kCamera, bad));
  EXPECT_EQ(s.camera_jpeg(), nullptr);
}

// ---- the log timeline ----

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

// ---- clients ----

Update text(const std::string& s) { return std::make_shared<const std::string>(s); }

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

// ---- the page's files ----

TEST(Assets, ThePageIsEmbeddedAndServedByExactNameOnly) {
  const Asset* index = find_asset("/");
  ASSERT_NE(index, nullptr);
  EXPECT_EQ(index->path, "/index.html");
  EXPECT_EQ(index->content_type, "text/html; charset=utf-8");
  EXPECT_NE(index->body.find("/viewer.js"), std::string_view::npos);
  ASSERT_NE(find_asset("/viewer.js"), nullptr);
  ASSERT_NE(find_asset("/viewer.css"), nullptr);
  EXPECT_EQ(find_asset("/viewer.js")->content_type, "text/javascript; charset=utf-8");
  for (const char* path : {"/../etc/passwd", "/%2e%2e/%2e%2e/etc/passwd", "/etc/passwd", "//index.html",
                           "/./index.html", "/index.html/", "index.html", "/INDEX.HTML", "/viewer.js/../index.html",
                           "/index.html%00", "", "/web/index.html", "/embed_assets.cmake"}) {
    EXPECT_EQ(find_asset(path), nullptr) << path;
  }
  EXPECT_EQ(find_asset(std::string_view("/index.html\0.png", 16)), nullptr);
  for (const Asset& a : embedded_assets()) {
    EXPECT_EQ(a.body.find("http://"), std::string_view::npos) << a.path << " loads nothing from elsewhere";
    EXPECT_EQ(a.body.find("https://"), std::string_view::npos) << a.path;
  }
}

}  // namespace
}  // namespace whiskeye::viewer
