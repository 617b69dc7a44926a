// slamd's messages ↔ the SLAM core's structs (wire_conversion.h).
#include "whiskeye/slamd/wire_conversion.h"

#include "whiskeye/common/whisker_array.h"

#include <cmath>
#include <whiskeye/vita_pose_t.hpp>

namespace whiskeye::slamd {

slam::WhiskCycleInput to_core(const whisk_cycle_t& m) {
  slam::WhiskCycleInput in;
  to_core(m, in);
  return in;
}

void to_core(const whisk_cycle_t& m, slam::WhiskCycleInput& in) {
  in.cycle = m.cycle;
  in.utime_start = m.utime_start;
  in.utime_end = m.utime_end;
  in.samples.resize(static_cast<std::size_t>(m.num_samples));
  for (int s = 0; s < m.num_samples; ++s) {
    slam::WhiskSample& out = in.samples[static_cast<std::size_t>(s)];
    out.utime = m.sample_utime[s];
    out.valid = m.sample_valid[s] != 0;
    for (int w = 0; w < kNumWhiskers; ++w) {
      out.theta[w] = m.theta[s][w];
      out.deflection_x[w] = m.deflection_x[s][w];
      out.deflection_y[w] = m.deflection_y[s][w];
      out.contact[w] = m.contact[s][w] != 0;
    }
  }
}

slam::OdometrySample to_core(const odometry_t& m) { return {m.utime, m.vx, m.vy, m.omega}; }

slam::ImageView to_core(const CameraFrame& f) {
  return slam::ImageView{f.utime, f.width, f.height, f.row_stride, static_cast<uint32_t>(f.pixelformat), f.data};
}

bool has_contact(const whisk_cycle_t& m) {
  for (std::size_t s = 0; s < m.contact.size(); ++s) {
    if (!m.sample_valid[s]) continue;
    for (int8_t c : m.contact[s]) {
      if (c) return true;
    }
  }
  return false;
}

int8_t mode_code(slam::Mode mode) {
  switch (mode) {
    case slam::Mode::Visual: return vita_pose_t::MODE_VISUAL;
    case slam::Mode::Tactile: return vita_pose_t::MODE_TACTILE;
    case slam::Mode::Vita: return vita_pose_t::MODE_VITA;
  }
  return vita_pose_t::MODE_VITA;
}

namespace {

int8_t event_code(slam::EventType type) {
  switch (type) {
    case slam::EventType::SameExperience: return vita_event_t::SAME_EXPERIENCE;
    case slam::EventType::NewExperience: return vita_event_t::NEW_EXPERIENCE;
    case slam::EventType::Relocalise: return vita_event_t::RELOCALISE;
  }
  return vita_event_t::SAME_EXPERIENCE;
}

}  // namespace

int8_t localisation_code(bool localising) {
  return localising ? vita_pose_t::LOCALISATION_LOCALISING : vita_pose_t::LOCALISATION_TRACKING;
}

vita_event_t event_message(const slam::CycleResult& r, int64_t utime, int64_t cycle, slam::Mode mode) {
  vita_event_t ev{};
  ev.utime = utime;
  ev.cycle = cycle;
  ev.type = event_code(r.event.type);
  ev.from_id = r.event.from_id;
  ev.to_id = r.event.to_id;
  ev.template_id = r.match.template_id;
  ev.mode = mode_code(mode);
  ev.localisation = localisation_code(r.localising);
  return ev;
}

template_match_t match_message(const slam::CycleResult& r, int64_t utime, int64_t cycle, slam::Mode mode) {
  template_match_t m{};
  m.utime = utime;
  m.cycle = cycle;
  m.template_id = r.match.template_id;
  m.is_new = r.match.is_new;
  m.error = r.match.error;
  m.visual_error = r.match.visual_error;
  m.pfh_error = r.match.pfh_error;
  m.sda_error = r.match.sda_error;
  m.visual_shift = r.match.visual_shift;
  m.num_templates = r.num_templates;
  m.mode = mode_code(mode);
  m.visual_used = r.match.visual_used;
  m.tactile_used = r.match.tactile_used;
  return m;
}

vita_map_t map_message(const slam::ExperienceMap& map, int64_t utime, slam::Mode mode) {
  vita_map_t msg{};
  msg.utime = utime;
  msg.mode = mode_code(mode);
  msg.current_experience_id = map.current_id();
  for (const auto& e : map.experiences()) {
    experience_t x{};
    x.id = e.id;
    x.x = e.pose.x;
    x.y = e.pose.y;
    x.theta = e.pose.theta;
    x.utime_created = e.utime_created;
    x.visual_template_id = e.visual_template_id;
    x.tactile_template_id = e.tactile_template_id;
    x.dense = e.dense;
    msg.experiences.push_back(x);
  }
  msg.num_experiences = static_cast<int32_t>(msg.experiences.size());
  for (const auto& l : map.links()) {
    link_t x{};
    x.from_id = l.from;
    x.to_id = l.to;
    x.dx = l.delta.x;
    x.dy = l.delta.y;
    x.dtheta = l.delta.theta;
    x.utime_created = l.utime_created;
    x.recognised_ends = static_cast<int8_t>(l.recognised_ends);
    x.sigma = std::sqrt(l.sigma2);
    x.scale = l.scale;
    x.revoked = l.revoked();
    msg.links.push_back(x);
  }
  msg.num_links = static_cast<int32_t>(msg.links.size());
  return msg;
}

}  // namespace whiskeye::slamd
