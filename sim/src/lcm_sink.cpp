// SimSink → LCM messages (see lcm_sink.h).
#include "whiskeye/sim/lcm_sink.h"

#include <whiskeye/contact_truth_t.hpp>
#include <whiskeye/odometry_t.hpp>
#include <whiskeye/pose2d_t.hpp>

#include <algorithm>
#include <cmath>

namespace whiskeye::sim {

namespace {

int16_t to_counts(double v, double scale) {
  return static_cast<int16_t>(std::clamp(std::lround(v * scale), -32768L, 32767L));
}

}  // namespace

whisker_sample_t to_lcm(const rcp::WhiskerSample& s, const WhiskerHealth& health, double saturation) {
  whisker_sample_t m;
  m.utime = s.utime;
  m.seq = s.seq;
  m.num_whiskers = rcp::kNumWhiskers;
  for (int w = 0; w < rcp::kNumWhiskers; ++w) {
    m.theta.push_back(static_cast<float>(s.theta[w]));
    m.deflection_x.push_back(static_cast<float>(s.deflection_x[w]));
    m.deflection_y.push_back(static_cast<float>(s.deflection_y[w]));
    m.raw_x.push_back(to_counts(s.deflection_x[w], kRawHallPerUnit));
    m.raw_y.push_back(to_counts(s.deflection_y[w], kRawHallPerUnit));
    m.raw_theta.push_back(to_counts(s.theta[w], kRawThetaPerRad));
    int8_t status = whisker_sample_t::STATUS_OK;
    if (std::max(std::abs(s.deflection_x[w]), std::abs(s.deflection_y[w])) >= saturation) {
      status |= whisker_sample_t::STATUS_SATURATED;
    }
    if (health.stale[w]) status |= whisker_sample_t::STATUS_STALE;
    if (health.fault[w] || (!s.valid[w] && !health.stale[w])) status |= whisker_sample_t::STATUS_FAULT;
    m.status.push_back(status);
  }
  return m;
}

rcp_state_t to_lcm(const rcp::ControlOutput& out) {
  rcp_state_t m;
  m.utime = out.utime;
  m.cycle = out.cycle;
  m.phase = static_cast<int8_t>(out.phase);
  m.cycle_phase = out.cycle_phase;
  m.enabled = out.enabled;
  m.num_whiskers = rcp::kNumWhiskers;
  for (int w = 0; w < rcp::kNumWhiskers; ++w) {
    m.contact.push_back(static_cast<float>(out.contact[w]));
    m.theta_ceiling.push_back(static_cast<float>(out.theta_ceiling[w]));
    m.theta_command.push_back(static_cast<float>(out.theta_command[w]));
  }
  return m;
}

whisk_cycle_t to_lcm(const rcp::WhiskCycle& c) {
  whisk_cycle_t m;
  m.utime = c.utime_end;
  m.cycle = c.cycle;
  m.utime_start = c.utime_start;
  m.utime_end = c.utime_end;
  m.num_whiskers = rcp::kNumWhiskers;
  m.num_samples = static_cast<int32_t>(c.samples.size());
  m.num_missing = c.num_missing;
  for (const rcp::WhiskCycle::Sample& s : c.samples) {
    m.sample_utime.push_back(s.utime);
    m.sample_valid.push_back(s.valid ? 1 : 0);
    m.phase.push_back(static_cast<int8_t>(s.phase));
    m.theta.emplace_back(s.theta.begin(), s.theta.end());
    m.deflection_x.emplace_back(s.deflection_x.begin(), s.deflection_x.end());
    m.deflection_y.emplace_back(s.deflection_y.begin(), s.deflection_y.end());
    std::vector<int8_t> contact(rcp::kNumWhiskers);
    for (int w = 0; w < rcp::kNumWhiskers; ++w) contact[static_cast<std::size_t>(w)] = s.contact[w] ? 1 : 0;
    m.contact.push_back(std::move(contact));
  }
  return m;
}

sim_fault_t to_lcm(const FaultEvent& e) {
  sim_fault_t m;
  m.utime = e.utime;
  m.kind = static_cast<int8_t>(e.kind);
  m.active = e.active;
  m.index = e.index;
  m.value = e.value;
  return m;
}

LcmSink::LcmSink(Bus& bus, std::function<void(int64_t)> set_time, bool yuyv, double saturation)
    : bus_(bus), set_time_(std::move(set_time)), yuyv_(yuyv), saturation_(saturation) {}

template <typename T>
void LcmSink::put(const std::string& channel, int64_t utime, const T& msg) {
  if (set_time_) set_time_(utime);
  publish(bus_, channel, msg);
  ++counts_[channel];
}

void LcmSink::whisker_sample(const rcp::WhiskerSample& sample, const WhiskerHealth& health) {
  put("WHISKER_SAMPLE", sample.utime, to_lcm(sample, health, saturation_));
}

void LcmSink::rcp_state(const rcp::ControlOutput& out) { put("RCP_STATE", out.utime, to_lcm(out)); }

void LcmSink::whisk_cycle(const rcp::WhiskCycle& cycle) { put("WHISK_CYCLE", cycle.utime_end, to_lcm(cycle)); }

void LcmSink::contact_truth(const ContactTruth& truth) {
  contact_truth_t m;
  m.utime = truth.utime;
  m.cycle = truth.cycle;
  m.num_points = static_cast<int32_t>(truth.points.size());
  for (const ContactTruth::Point& p : truth.points) {
    m.whisker.push_back(p.whisker);
    m.point_utime.push_back(p.utime);
    m.x.push_back(p.p_in_head.x);
    m.y.push_back(p.p_in_head.y);
    m.z.push_back(p.p_in_head.z);
  }
  put("SIM_CONTACT_TRUTH", truth.utime, m);
}

void LcmSink::odometry(int64_t utime, int64_t seq, const OdometrySample& odom) {
  odometry_t m;
  m.utime = utime;
  m.seq = seq;
  m.x = odom.pose.x;
  m.y = odom.pose.y;
  m.theta = odom.pose.theta;
  m.vx = odom.vx;
  m.vy = odom.vy;
  m.omega = odom.omega;
  put("ODOMETRY", utime, m);
}

void LcmSink::ground_truth(int64_t utime, const Pose2& T_world_base) {
  pose2d_t m;
  m.utime = utime;
  m.x = T_world_base.x;
  m.y = T_world_base.y;
  m.theta = T_world_base.theta;
  put("GROUND_TRUTH", utime, m);
}

void LcmSink::camera(int64_t utime, int64_t seq, const std::vector<uint8_t>& grey, int width, int height) {
  image_.utime = utime;
  image_.seq = seq;
  image_.width = width;
  image_.height = height;
  if (yuyv_) {
    grey_to_yuyv(grey, width, height, image_.data);
    image_.row_stride = 2 * width;
    image_.pixelformat = image_t::PIXEL_FORMAT_YUYV;
  } else {
    image_.data = grey;
    image_.row_stride = width;
    image_.pixelformat = image_t::PIXEL_FORMAT_GREY;
  }
  image_.size = static_cast<int32_t>(image_.data.size());
  put("CAMERA", utime, image_);
}

void LcmSink::fault(const FaultEvent& event) { put("SIM_FAULT", event.utime, to_lcm(event)); }

}  // namespace whiskeye::sim
