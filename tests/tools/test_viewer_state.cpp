// ViewerState: the viewer's aggregated state and its JSON, from the messages it is fed.
#include "viewer_messages.h"

#include "whiskeye/common/channels.h"
#include "whiskeye/viewer/camera_jpeg.h"
#include "whiskeye/viewer/viewer_state.h"

#include "hostile_jpeg.h"

#include <gtest/gtest.h>
#include <opencv2/imgcodecs.hpp>

#include <cmath>
#include <limits>

namespace whiskeye::viewer {
namespace {

using namespace whiskeye::viewer::test;
using nlohmann::json;

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
  EXPECT_EQ(map["revoked"], json({0, 0, 0, 0}));
  EXPECT_EQ(map["num_revoked"], 0);
}

// A link the back end revoked is flagged, so that the page draws it apart.
TEST(ViewerState, ALinkTheBackEndRevokedIsFlaggedAndCounted) {
  ViewerState s;
  vita_map_t m = make_map(4, 0);
  link_t wrong{};
  wrong.from_id = 3;
  wrong.to_id = 1;
  wrong.scale = 1e-4;
  wrong.revoked = true;
  m.links.push_back(wrong);
  m.num_links = static_cast<int32_t>(m.links.size());
  ASSERT_TRUE(feed(s, channels::kVitaMap, m));
  const json map = s.snapshot()["map"];
  EXPECT_EQ(map["revoked"], json({0, 0, 0, 1}));
  EXPECT_EQ(map["num_revoked"], 1);
}

// The page shows LOCALISING: the pose claims nothing while slamd does not know where it is.
TEST(ViewerState, ThePoseSaysWhetherSlamdIsLocalising) {
  ViewerState s;
  vita_pose_t p = make_pose(1.0, 2.0);
  ASSERT_TRUE(feed(s, channels::kVitaPose, p));
  EXPECT_EQ(s.snapshot()["pose"]["localising"], false);
  p.localisation = vita_pose_t::LOCALISATION_LOCALISING;
  p.utime += 100000;
  ASSERT_TRUE(feed(s, channels::kVitaPose, p));
  EXPECT_EQ(s.snapshot()["pose"]["localising"], true);
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

// /api/camera.jpg of a frame hiding a 32000 x 32000 progressive header behind a 640x480 one took the
// viewer from 52 MB to 1.18 GB (MemoryMax=512M on the robot): refused from libjpeg's own header.
TEST(ViewerState, AnMjpegFrameHidingAHugeHeaderIsNotShownAndSaysWhy) {
  const std::vector<uint8_t> hostile = whiskeye::test::camera_frame_hiding_progressive(640, 480, 32000, 32000);
  Frame f;
  f.utime = kT0;
  f.width = 640;
  f.height = 480;
  f.pixelformat = image_t::PIXEL_FORMAT_MJPEG;
  f.data = hostile;
  std::string reason;
  EXPECT_EQ(frame_to_jpeg(f, 320, 80, &reason), nullptr);
  EXPECT_EQ(reason, "image: MJPEG frame is 32000x32000 by its JPEG header, the message says 640x480");
}

}  // namespace
}  // namespace whiskeye::viewer
