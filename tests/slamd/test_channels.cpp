// Channel names across daemons: a channel renamed in whiskerd.yaml and in slam.yaml alike still
// connects whiskerd's publisher to slamd's subscriber, and renamed in one of them only it does not
// (the silent disconnection the configurable names guard against: docs/lcm-channels.md, "Renaming a
// channel"). Through the bus seam: whiskerd's conversion publishes on its configured channel, the
// slamd node reads its own, on one in-memory bus.
#include "whiskeye/slamd/slam_node.h"
#include "whiskeye/whiskerd/config.h"
#include "whiskeye/whiskerd/lcm.h"

#include <whiskeye/odometry_t.hpp>
#include <whiskeye/vita_event_t.hpp>

#include <gtest/gtest.h>

#include <cmath>
#include <memory>

namespace whiskeye::slamd {
namespace {

constexpr int64_t kT0 = 1'700'000'000'000'000;
constexpr int64_t kS = 1'000'000;

// A contact-free whisk cycle of 1 s at 500 Hz ending at `end`, as the controller assembles it.
rcp::WhiskCycle free_cycle(int64_t n, int64_t end) {
  rcp::WhiskCycle c;
  c.cycle = n;
  c.utime_start = end - kS + 2000;
  c.utime_end = end;
  for (int s = 0; s < 500; ++s) {
    rcp::WhiskCycle::Sample sample;
    sample.utime = c.utime_start + s * 2000;
    sample.valid = true;
    sample.phase = s < 250 ? rcp::Phase::Protract : rcp::Phase::Retract;
    sample.theta.fill(static_cast<float>(0.6 * std::sin(kTwoPi * s / 500.0)));
    c.samples.push_back(sample);
  }
  return c;
}

struct Wiring {
  whiskerd::Params whiskerd;
  NodeParams slamd;
};

Wiring load_configs(const std::string& whiskerd_yaml, const std::string& slam_yaml) {
  Wiring w;
  whiskerd::load(ParamNode::from_string(whiskerd_yaml, "whiskerd.yaml"), w.whiskerd);
  const ParamNode slam = ParamNode::from_string(slam_yaml, "slam.yaml");
  load(slam.section("slamd"), w.slamd);
  return w;
}

// Runs whiskerd's WHISK_CYCLE (on its configured channel) and odometry into a tactile slamd node for
// three seconds; returns the VITA_EVENTs seen on the node's configured event channel.
int events_through(const Wiring& w) {
  MemoryBus bus;
  DecodeErrors errors;
  slam::SlamParams p;
  p.mode = slam::Mode::Tactile;
  SlamNode node(bus, bus, std::make_unique<slam::VitaSlam>(p, default_robot_geometry()), w.slamd, errors);
  int events = 0;
  subscribe<vita_event_t>(bus, w.slamd.channels.event, [&](const vita_event_t&) { ++events; }, errors);
  for (int sec = 0; sec < 3; ++sec) {
    for (int k = 1; k <= 50; ++k) {
      const int64_t t = kT0 + sec * kS + k * 20'000;
      odometry_t o{};
      o.utime = t;
      publish(bus, channels::kOdometry, o);
      if (k == 50) {
        whisk_cycle_t msg;
        to_lcm(free_cycle(sec, t), msg);
        publish(bus, w.whiskerd.channel_cycle, msg);
      }
    }
  }
  node.flush();
  return events;
}

TEST(Channels, DefaultsAreTheNamesOfChannelsH) {
  const Wiring w = load_configs("", "");
  EXPECT_EQ(w.whiskerd.channel_cycle, channels::kWhiskCycle);
  EXPECT_EQ(w.slamd.channels.cycle, channels::kWhiskCycle);
  EXPECT_EQ(w.slamd.channels.event, channels::kVitaEvent);
  EXPECT_EQ(events_through(w), 3);
}

TEST(Channels, AWhiskCycleRenamedInBothConfigsStillConnectsWhiskerdToSlamd) {
  const Wiring w = load_configs("lcm:\n  channel_cycle: WHISK_CYCLE_LEFT\n",
                                "slamd:\n  channel_cycle: WHISK_CYCLE_LEFT\n  channel_event: VITA_EVENT_LEFT\n");
  EXPECT_EQ(w.slamd.channels.cycle, "WHISK_CYCLE_LEFT");
  EXPECT_EQ(events_through(w), 3);
}

TEST(Channels, AWhiskCycleRenamedInWhiskerdOnlyReachesNoSlamd) {
  const Wiring w = load_configs("lcm:\n  channel_cycle: WHISK_CYCLE_LEFT\n", "");
  EXPECT_EQ(events_through(w), 0);
}

// slamd's channels as slam.yaml (or a --set) names them: "" when accepted, else the ParamError.
std::string channels_error(const std::string& slamd_yaml, const std::string& set_key = "",
                           const std::string& set_value = "") {
  try {
    ParamNode root = ParamNode::from_string(slamd_yaml, "slam.yaml");
    if (!set_key.empty()) root.set_override(set_key, set_value, "--set");
    NodeParams p;
    load(root.section("slamd"), p);
    return "";
  } catch (const ParamError& e) {
    return e.what();
  }
}

// channel_pose=GROUND_TRUTH wrote slamd's poses into the replay's ground truth (vita-eval then said
// LEM n/a and exited 0): no slamd channel may be the stack's channel of another type.
TEST(Channels, ASlamdChannelNamingAnotherTypesChannelIsRefused) {
  EXPECT_EQ(channels_error("slamd: {channel_pose: GROUND_TRUTH}\n"),
            "slam.yaml: 'slamd.channel_pose' = \"GROUND_TRUTH\" is the stack's channel of pose2d_t, not of vita_pose_t "
            "(common/channels.h): give slamd's channel a name of its own");
  EXPECT_EQ(channels_error("", "slamd.channel_event", "SIM_FAULT"),
            "--set: 'slamd.channel_event' = \"SIM_FAULT\" is the stack's channel of sim_fault_t, not of vita_event_t "
            "(common/channels.h): give slamd's channel a name of its own");
  EXPECT_NE(channels_error("slamd: {channel_map: SIM_CONTACT_TRUTH}\n"), "");
  EXPECT_NE(channels_error("slamd: {channel_status: DRIVER_STATUS}\n"), "");
  EXPECT_NE(channels_error("slamd: {channel_odometry: BASE_CMD}\n"), "") << "an input too";
  EXPECT_NE(channels_error("slamd: {channel_pose: VITA_MAP, channel_map: MAP_2}\n"), "");
  EXPECT_EQ(channels_error("slamd: {channel_pose: VITA_POSE, channel_camera: CAMERA}\n"), "") << "their own names";
}

TEST(Channels, TwoSlamdChannelsOfOneNameAreRefused) {
  EXPECT_EQ(channels_error("slamd: {channel_pose: OUT, channel_map: OUT}\n"),
            "slam.yaml: 'slamd.channel_map' = \"OUT\" is 'slamd.channel_pose' too: each of slamd's channels needs a "
            "name of its own");
  EXPECT_NE(channels_error("slamd: {channel_cycle: LEFT, channel_status: LEFT}\n"), "") << "an output onto an input";
  EXPECT_NE(channels_error("slamd: {channel_cycle: LEFT, channel_camera: LEFT}\n"), "") << "two inputs";
}

// `key` set to `value` by a --set is refused with `what` in the line.
void expect_refused(const std::string& key, const std::string& value, const std::string& what) {
  const std::string error = channels_error("", key, value);
  EXPECT_NE(error.find("--set: '" + key + "' = " + what), std::string::npos) << error;
}

// LCM's publish refuses a name over 63 characters, and it subscribes by regular expression.
TEST(Channels, ANameOutsideLcmsCharactersOrLengthIsRefusedShownPrintably) {
  EXPECT_EQ(channels_error("slamd: {channel_pose: " + std::string(63, 'P') + "}\n"), "");
  EXPECT_EQ(channels_error("slamd: {channel_pose: robot-2/VITA_POSE}\n"), "");
  EXPECT_EQ(channels_error("slamd: {channel_pose: " + std::string(300, 'P') + "}\n"),
            "slam.yaml: 'slamd.channel_pose' = \"" + std::string(40, 'P') +
                "...\" (300 characters) is no channel name: 1 to 63 of A-Z a-z 0-9 _ - / (LCM's limit; it subscribes "
                "by regular expression)");
  EXPECT_NE(channels_error("slamd: {channel_pose: " + std::string(64, 'P') + "}\n"), "");
  expect_refused("slamd.channel_pose", "VITA\xff\xfePOSE", "\"VITA\\xff\\xfePOSE\" is no channel name");
  expect_refused("slamd.channel_event", "VITA EVENT", "\"VITA EVENT\" is no channel name");
  expect_refused("slamd.channel_cycle", "WHISK.*", "\"WHISK.*\" is no channel name");
  expect_refused("slamd.channel_map", "", "\"\" is no channel name");
}

}  // namespace
}  // namespace whiskeye::slamd
