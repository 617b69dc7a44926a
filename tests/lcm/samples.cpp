#include "samples.h"

#include "whiskeye/common/bus.h"

#include <whiskeye/base_cmd_t.hpp>
#include <whiskeye/contact_truth_t.hpp>
#include <whiskeye/driver_status_t.hpp>
#include <whiskeye/image_t.hpp>
#include <whiskeye/odometry_t.hpp>
#include <whiskeye/pose2d_t.hpp>
#include <whiskeye/rcp_state_t.hpp>
#include <whiskeye/sim_fault_t.hpp>
#include <whiskeye/slam_status_t.hpp>
#include <whiskeye/template_match_t.hpp>
#include <whiskeye/vita_event_t.hpp>
#include <whiskeye/vita_map_t.hpp>
#include <whiskeye/vita_pose_t.hpp>
#include <whiskeye/whisk_cycle_t.hpp>
#include <whiskeye/whisker_sample_t.hpp>

namespace whiskeye::testing {
namespace {

template <typename T>
TypeSample make(const T& msg) {
  TypeSample s;
  s.type = T::getTypeName();
  s.channel = "TEST_" + s.type;
  s.bytes = encode_message(msg);
  const std::vector<uint8_t> expected = s.bytes;
  s.round_trips = [expected](std::span<const uint8_t> data) {
    T decoded;
    if (!decode_message(data, decoded)) return false;
    return encode_message(decoded) == expected;
  };
  return s;
}

constexpr int64_t kT = 1'700'000'000'123'456;

}  // namespace

std::vector<TypeSample> all_type_samples() {
  std::vector<TypeSample> out;
  {
    pose2d_t m{};
    m.utime = kT;
    m.x = 1.25;
    m.y = -0.5;
    m.theta = 3.0;
    out.push_back(make(m));
  }
  {
    whisker_sample_t m{};
    m.utime = kT;
    m.seq = 42;
    m.num_whiskers = 24;
    for (int w = 0; w < 24; ++w) {
      m.theta.push_back(0.01f * w);
      m.deflection_x.push_back(-0.02f * w);
      m.deflection_y.push_back(0.03f * w);
      m.raw_x.push_back(static_cast<int16_t>(-40 * w));
      m.raw_y.push_back(static_cast<int16_t>(60 * w));
      m.raw_theta.push_back(static_cast<int16_t>(1000 + w));
      // LCM 1.3.1 constants are declared without a definition: use them by value only (unary +).
      m.status.push_back(static_cast<int8_t>(w == 3 ? +whisker_sample_t::STATUS_STALE : +whisker_sample_t::STATUS_OK));
    }
    out.push_back(make(m));
  }
  {
    rcp_state_t m{};
    m.utime = kT;
    m.cycle = 7;
    m.phase = rcp_state_t::PHASE_RETRACT;
    m.cycle_phase = 0.6;
    m.enabled = true;
    m.num_whiskers = 24;
    m.contact.assign(24, 0.5f);
    m.theta_ceiling.assign(24, 0.7f);
    m.theta_command.assign(24, -0.2f);
    out.push_back(make(m));
  }
  {
    whisk_cycle_t m{};
    m.utime = kT;
    m.cycle = 3;
    m.utime_start = kT - 1'000'000;
    m.utime_end = kT;
    m.num_whiskers = 24;
    m.num_samples = 5;
    m.num_missing = 1;
    for (int s = 0; s < 5; ++s) {
      m.sample_utime.push_back(kT - 1'000'000 + s * 2000);
      m.sample_valid.push_back(s == 2 ? 0 : 1);
      m.phase.push_back(s < 3 ? 0 : 1);
      m.theta.push_back(std::vector<float>(24, 0.1f * s));
      m.deflection_x.push_back(std::vector<float>(24, 0.01f * s));
      m.deflection_y.push_back(std::vector<float>(24, -0.01f * s));
      m.contact.push_back(std::vector<int8_t>(24, s > 3 ? 1 : 0));
    }
    out.push_back(make(m));
  }
  {
    image_t m{};
    m.utime = kT;
    m.seq = 9;
    m.width = 8;
    m.height = 4;
    m.row_stride = 16;
    m.pixelformat = image_t::PIXEL_FORMAT_YUYV;
    m.size = 64;
    for (int i = 0; i < 64; ++i) m.data.push_back(static_cast<uint8_t>(i * 3));
    out.push_back(make(m));
  }
  {
    odometry_t m{};
    m.utime = kT;
    m.seq = 100;
    m.x = 0.5;
    m.y = 0.25;
    m.theta = -1.0;
    m.vx = 0.0;
    m.vy = 0.15;
    m.omega = 0.15;
    out.push_back(make(m));
  }
  {
    base_cmd_t m{};
    m.utime = kT;
    m.vx = 0.1;
    m.vy = -0.2;
    m.omega = 0.3;
    out.push_back(make(m));
  }
  {
    vita_pose_t m{};
    m.utime = kT;
    m.x = 1;
    m.y = 2;
    m.theta = 0.5;
    m.experience_id = 12;
    m.template_id = 4;
    m.mode = vita_pose_t::MODE_VITA;
    m.pose_cell_x = 10.5;
    m.pose_cell_y = 3.25;
    m.pose_cell_theta = 20.0;
    out.push_back(make(m));
  }
  {
    vita_event_t m{};
    m.utime = kT;
    m.cycle = 55;
    m.type = vita_event_t::RELOCALISE;
    m.from_id = 30;
    m.to_id = 2;
    m.template_id = 2;
    m.mode = vita_pose_t::MODE_TACTILE;
    out.push_back(make(m));
  }
  {
    template_match_t m{};
    m.utime = kT;
    m.cycle = 55;
    m.template_id = 2;
    m.is_new = false;
    m.error = 0.04;
    m.visual_error = 0.03;
    m.pfh_error = 0.005;
    m.sda_error = 0.005;
    m.visual_shift = -2;
    m.num_templates = 40;
    m.mode = vita_pose_t::MODE_VITA;
    m.visual_used = true;
    m.tactile_used = true;
    out.push_back(make(m));
  }
  experience_t e{};
  e.id = 1;
  e.x = 0.1;
  e.y = 0.2;
  e.theta = 0.3;
  e.utime_created = kT - 5;
  e.visual_template_id = 1;
  e.tactile_template_id = 1;
  e.dense = true;
  out.push_back(make(e));
  link_t l{};
  l.from_id = 0;
  l.to_id = 1;
  l.dx = 0.1;
  l.dy = 0.0;
  l.dtheta = 0.05;
  l.utime_created = kT - 5;
  out.push_back(make(l));
  {
    vita_map_t m{};
    m.utime = kT;
    m.mode = vita_pose_t::MODE_VITA;
    m.current_experience_id = 1;
    m.num_experiences = 2;
    m.experiences = {e, e};
    m.experiences[0].id = 0;
    m.num_links = 1;
    m.links = {l};
    out.push_back(make(m));
  }
  {
    driver_status_t m{};
    m.utime = kT;
    m.driver = "whiskerd";
    m.state = driver_status_t::STATE_DEGRADED;
    m.message = "board 3 silent";
    m.num_counters = 2;
    m.counter_names = {"frames", "gaps_board3"};
    m.counter_values = {123456, 7};
    m.num_stats = 1;
    m.stat_names = {"loop_latency_p99_us"};
    m.stat_values = {85.5};
    out.push_back(make(m));
  }
  {
    slam_status_t m{};
    m.utime = kT;
    m.mode = vita_pose_t::MODE_VITA;
    m.state = driver_status_t::STATE_OK;
    m.message = "";
    m.cycles = 100;
    m.num_templates = 50;
    m.num_experiences = 60;
    m.num_links = 70;
    m.latency_last_ms = 1.5;
    m.latency_p50_ms = 1.2;
    m.latency_p99_ms = 3.4;
    m.latency_max_ms = 5.0;
    m.decode_errors = 1;
    m.validation_errors = 2;
    m.cycles_without_camera = 3;
    m.cycles_without_contact = 4;
    m.checkpoints_written = 100;
    m.checkpoint_errors = 0;
    m.checkpoints_superseded = 2;
    out.push_back(make(m));
  }
  {
    contact_truth_t m{};
    m.utime = kT;
    m.cycle = 3;
    m.num_points = 2;
    m.whisker = {4, 17};
    m.point_utime = {kT - 10, kT - 5};
    m.x = {0.1, 0.12};
    m.y = {0.05, -0.04};
    m.z = {0.0, -0.02};
    out.push_back(make(m));
  }
  {
    sim_fault_t m{};
    m.utime = kT;
    m.kind = sim_fault_t::KIND_ODOMETRY_SLIP;
    m.active = true;
    m.index = -1;
    m.value = 1.2;
    out.push_back(make(m));
  }
  return out;
}

}  // namespace whiskeye::testing
