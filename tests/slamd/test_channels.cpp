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

}  // namespace
}  // namespace whiskeye::slamd
