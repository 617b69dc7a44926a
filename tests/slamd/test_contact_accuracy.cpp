// How well slamd's tactile front end (slam::estimate_contacts: contact detection and the contact
// point from θ and deflection) recovers the simulator's true contacts. vita-sim drives the default
// arena for its four revolutions (each tactile landmark touched four times); every WHISK_CYCLE of its log goes through
// the same conversion and estimator as in slamd, and is compared with SIM_CONTACT_TRUTH of that cycle
// (the true point where each whisker first touched, head frame). Guards the figures quoted in
// docs/slam-core.md ("Contact points").
#include "scratch.h"
#include "whiskeye/slamd/wire_conversion.h"
#include "subprocess.h"

#include "whiskeye/common/bus.h"
#include "whiskeye/common/robot_geometry.h"
#include "whiskeye/slam/tactile_template.h"

#include <whiskeye/contact_truth_t.hpp>
#include <whiskeye/whisk_cycle_t.hpp>

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <vector>

namespace whiskeye::slamd {
namespace {

struct Truth {
  int64_t utime = 0;
  Vec3 p;
};

double quantile(std::vector<double> v, double q) {
  std::sort(v.begin(), v.end());
  return v[static_cast<size_t>(q * static_cast<double>(v.size() - 1))];
}

TEST(ContactAccuracy, EstimatedContactPointsAreNearTheSimulatorsTrueOnes) {
  const std::string log = whiskeye::testing::scratch_file("contact_accuracy", ".lcmlog");
  whiskeye::testing::Subprocess sim({VITA_SIM_EXE, "--world", WHISKEYE_SOURCE_DIR "/config/worlds/aliased_arena.yaml",
                                     "--robot", WHISKEYE_SOURCE_DIR "/config/robot.yaml", "--seed", "1",
                                     "--quiet", "--output", log});
  ASSERT_EQ(sim.wait(120.0), 0) << sim.output();

  RobotGeometry geometry = default_robot_geometry();
  load(ParamNode::from_file(WHISKEYE_SOURCE_DIR "/config/robot.yaml").section("robot"), geometry);
  slam::TactileParams params;
  load(ParamNode::from_file(WHISKEYE_SOURCE_DIR "/config/slam.yaml").section("slam").section("tactile"), params);

  std::map<int64_t, whisk_cycle_t> cycles;
  std::map<int64_t, std::map<int, Truth>> truth;  // cycle → whisker → its first true contact
  LogReader reader(log);
  LogReader::EventView ev;
  while (reader.next(ev)) {
    if (ev.channel == "WHISK_CYCLE") {
      whisk_cycle_t m;
      ASSERT_GE(m.decode(ev.data.data(), 0, static_cast<int>(ev.data.size())), 0);
      cycles[m.cycle] = m;
    } else if (ev.channel == "SIM_CONTACT_TRUTH") {
      contact_truth_t m;
      ASSERT_GE(m.decode(ev.data.data(), 0, static_cast<int>(ev.data.size())), 0);
      auto& per_whisker = truth[m.cycle];
      for (int i = 0; i < m.num_points; ++i) {
        const auto [it, fresh] = per_whisker.try_emplace(m.whisker[i], Truth{m.point_utime[i], {m.x[i], m.y[i], m.z[i]}});
        if (!fresh && m.point_utime[i] < it->second.utime) it->second = Truth{m.point_utime[i], {m.x[i], m.y[i], m.z[i]}};
      }
    }
  }
  ASSERT_GE(cycles.size(), 240u);

  std::vector<double> errors;
  int truly_touching = 0, detected = 0, false_contacts = 0, estimated = 0;
  for (const auto& [cycle, msg] : cycles) {
    const auto estimates = slam::estimate_contacts(to_core(msg), geometry, params);
    const auto t = truth.find(cycle);
    const std::map<int, Truth> none;
    const auto& true_contacts = t != truth.end() ? t->second : none;
    truly_touching += static_cast<int>(true_contacts.size());
    for (const auto& e : estimates) {
      ++estimated;
      const auto hit = true_contacts.find(e.whisker);
      if (hit == true_contacts.end()) {
        ++false_contacts;
        continue;
      }
      ++detected;
      const Vec3& a = e.p_contact_in_head;
      const Vec3& b = hit->second.p;
      errors.push_back(std::hypot(a.x - b.x, a.y - b.y, a.z - b.z));
    }
  }
  ASSERT_GE(truly_touching, 150) << "four laps past three tactile landmarks";
  ASSERT_FALSE(errors.empty());
  const double median = quantile(errors, 0.5), p90 = quantile(errors, 0.9);
  const double detection = static_cast<double>(detected) / truly_touching;
  const double false_rate = static_cast<double>(false_contacts) / std::max(1, estimated);
  std::printf("contact accuracy over %zu cycles: %d true whisker contacts, %.3f detected, %.3f of estimates false; "
              "point error median %.1f mm, p90 %.1f mm\n",
              cycles.size(), truly_touching, detection, false_rate, median * 1e3, p90 * 1e3);
  EXPECT_GE(detection, 0.85);
  EXPECT_LE(false_rate, 0.05);
  EXPECT_LE(median, 0.030);
  EXPECT_LE(p90, 0.080);
}

}  // namespace
}  // namespace whiskeye::slamd
