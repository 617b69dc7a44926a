// The viewer's aggregated state and its JSON (viewer_state.h).
#include "whiskeye/viewer/viewer_state.h"

#include "whiskeye/common/channels.h"
#include "whiskeye/common/message_layout.h"  // the checks of WHISK_CYCLE and CAMERA messages slamd applies too
#include "whiskeye/common/robot_geometry.h"
#include "whiskeye/common/wire_names.h"

#include <algorithm>
#include <cmath>

namespace whiskeye::viewer {

using nlohmann::json;

namespace {

// Positions to the millimetre and angles to the milliradian: the page draws pixels, and short
// numbers keep the JSON small.
double mm(double v) { return std::isfinite(v) ? std::round(v * 1000.0) / 1000.0 : 0.0; }

// A finite double for JSON (NaN and infinity are not JSON numbers).
json number(double v) { return std::isfinite(v) ? json(v) : json(nullptr); }

}  // namespace

bool is_latest_only(std::string_view channel) {
  return channel == channels::kCamera || channel == channels::kWhiskCycle || channel == channels::kVitaMap;
}

const char* state_name(int8_t state) {
  switch (state) {
    case driver_status_t::STATE_STARTING: return "starting";
    case driver_status_t::STATE_OK: return "ok";
    case driver_status_t::STATE_DEGRADED: return "degraded";
    case driver_status_t::STATE_FAULT: return "fault";
  }
  return "unknown";
}

ViewerState::ViewerState(ViewerParams params) : params_(params) {
  // Every section is new to a fresh Cursor, empty ones too (a page starts from a clean slate).
  for (int s = 0; s < kSections; ++s) bump(static_cast<Section>(s));
}

int64_t ViewerState::messages(std::string_view channel) const {
  const auto it = messages_.find(channel);
  return it == messages_.end() ? 0 : it->second;
}

void ViewerState::received(std::string_view channel, int64_t recv_utime) {
  auto it = messages_.find(channel);
  if (it == messages_.end()) it = messages_.emplace(std::string(channel), 0).first;
  ++it->second;
  if (recv_utime > now_utime_) set_now(recv_utime);
  bump(kMeta);
}

void ViewerState::decode_error(std::string_view channel, const std::string& reason) {
  ++decode_errors_;
  last_decode_error_ = std::string(channel) + ": " + reason;
  bump(kMeta);
}

void ViewerState::skip(std::string_view channel, int64_t recv_utime) { received(channel, recv_utime); }

void ViewerState::set_now(int64_t utime) {
  now_utime_ = utime;
  for (auto& [name, d] : daemons_) {
    const bool stale = now_utime_ - d.recv_utime > params_.status_stale_us;
    if (stale != d.stale) {
      d.stale = stale;
      bump(kStatus);
    }
  }
}

bool ViewerState::apply(std::string_view channel, int64_t recv_utime, std::span<const uint8_t> data,
                        std::shared_ptr<const void> owner) {
  std::string reason;
  // Decodes a T and hands it to `show`; a message that does not decode is counted instead.
  const auto take = [&]<typename T>(T msg, auto show) {
    if (!decode_message(data, msg, &reason)) {
      decode_error(channel, reason);
      return false;
    }
    received(channel, recv_utime);
    show(msg);
    return true;
  };
  if (channel == channels::kVitaMap) return take(vita_map_t{}, [&](const vita_map_t& m) { on_map(m); });
  if (channel == channels::kVitaPose) return take(vita_pose_t{}, [&](const vita_pose_t& m) { on_pose(m); });
  if (channel == channels::kVitaEvent) return take(vita_event_t{}, [&](const vita_event_t& m) { on_event(m); });
  if (channel == channels::kVitaMatch) return take(template_match_t{}, [&](const template_match_t& m) { on_match(m); });
  if (channel == channels::kDriverStatus) {
    return take(driver_status_t{}, [&](const driver_status_t& m) { on_driver_status(m, recv_utime); });
  }
  if (channel == channels::kSlamStatus) {
    return take(slam_status_t{}, [&](const slam_status_t& m) { on_slam_status(m, recv_utime); });
  }
  if (channel == channels::kWhiskCycle) {
    // slamd's checks, in its order: the counts against the length, then against the contract, before
    // the generated decoder allocates what the counts claim.
    reason = whisk_cycle_size_error(data);
    if (reason.empty()) reason = whisk_cycle_contract_error(data);
    if (!reason.empty()) {
      decode_error(channel, reason);
      return false;
    }
    return take(whisk_cycle_t{}, [&](const whisk_cycle_t& m) { on_whisk_cycle(m); });
  }
  if (channel == channels::kCamera) {
    Frame f;
    if (!decode_camera_frame(data, f, &reason)) {
      decode_error(channel, reason);
      return false;
    }
    if (std::string bad = camera_frame_error(f); !bad.empty()) {
      decode_error(channel, bad);
      return false;
    }
    received(channel, recv_utime);
    if (owner) {
      f.owner = std::move(owner);  // the bytes outlive this call: keep a view
    } else {
      own_pixels(f);
    }
    on_camera(std::move(f));
    return true;
  }
  return false;
}

void ViewerState::on_map(const vita_map_t& m) {
  map_ = m;
  have_map_ = true;
  num_dense_ = static_cast<int>(std::count_if(m.experiences.begin(), m.experiences.end(),
                                              [](const experience_t& e) { return e.dense; }));
  bump(kMap);
}

void ViewerState::on_pose(const vita_pose_t& m) {
  pose_ = m;
  have_pose_ = true;
  bump(kPose);
  if (!std::isfinite(m.x) || !std::isfinite(m.y)) return;
  if (!trail_.empty()) {
    const Point& last = trail_.back();
    if (std::hypot(m.x - last.x, m.y - last.y) < params_.trail_min_step_m) return;
  }
  trail_.push_back({m.x, m.y});
  while (trail_.size() > params_.trail_max_points) trail_.pop_front();
  bump(kTrail);
}

void ViewerState::on_event(const vita_event_t& m) {
  event_ = m;
  have_event_ = true;
  if (m.type >= 0 && m.type < static_cast<int8_t>(event_counts_.size())) ++event_counts_[static_cast<std::size_t>(m.type)];
  bump(kEvent);
}

void ViewerState::on_match(const template_match_t& m) {
  match_ = m;
  have_match_ = true;
  bump(kMatch);
}

void ViewerState::on_whisk_cycle(const whisk_cycle_t& m) {
  Whiskers w;
  w.cycle = m.cycle;
  w.utime = m.utime_end;
  w.num_samples = m.num_samples;
  w.num_missing = m.num_missing;
  const auto n = static_cast<std::size_t>(m.num_whiskers);
  w.contact.assign(n, false);
  w.measured.assign(n, false);
  w.deflection.assign(n, 0.0);
  w.theta_max.assign(n, 0.0);
  for (int s = 0; s < m.num_samples; ++s) {
    if (!m.sample_valid[s]) continue;
    for (std::size_t i = 0; i < n; ++i) {
      const double theta = m.theta[s][i];
      const double dx = m.deflection_x[s][i], dy = m.deflection_y[s][i];
      if (std::isnan(theta) || !std::isfinite(dx) || !std::isfinite(dy)) continue;  // not measured
      if (!w.measured[i]) w.theta_max[i] = theta;
      w.measured[i] = true;
      w.theta_max[i] = std::max(w.theta_max[i], theta);
      w.deflection[i] = std::max(w.deflection[i], std::hypot(dx, dy));
      if (m.contact[s][i]) w.contact[i] = true;
    }
  }
  whiskers_ = std::move(w);
  have_whiskers_ = true;
  bump(kWhiskers);
}

void ViewerState::on_camera(Frame frame) {
  frame_ = std::move(frame);
  have_frame_ = true;
  jpeg_.reset();
  jpeg_tried_ = false;
  bump(kCamera);
}

// A daemon's card: what every status message says (state, message, its time, when it came).
template <typename Status>
ViewerState::Daemon& ViewerState::status_record(const std::string& name, const char* kind, const Status& m,
                                                int64_t recv_utime) {
  Daemon& d = daemons_[name];
  d.kind = kind;
  d.state = m.state;
  d.message = m.message;
  d.utime = m.utime;
  d.recv_utime = recv_utime;
  d.stale = now_utime_ - recv_utime > params_.status_stale_us;
  return d;
}

void ViewerState::on_driver_status(const driver_status_t& m, int64_t recv_utime) {
  Daemon& d = status_record(m.driver, "driver", m, recv_utime);
  d.counters.clear();
  d.stats.clear();
  for (int i = 0; i < m.num_counters; ++i) d.counters.emplace_back(m.counter_names[i], static_cast<double>(m.counter_values[i]));
  for (int i = 0; i < m.num_stats; ++i) d.stats.emplace_back(m.stat_names[i], m.stat_values[i]);
  bump(kStatus);
}

void ViewerState::on_slam_status(const slam_status_t& m, int64_t recv_utime) {
  Daemon& d = status_record("slamd", "slam", m, recv_utime);
  const auto i64 = [](int64_t v) { return static_cast<double>(v); };
  d.counters = {{"cycles", i64(m.cycles)},
                {"templates", m.num_templates},
                {"experiences", m.num_experiences},
                {"links", m.num_links},
                {"decode_errors", i64(m.decode_errors)},
                {"validation_errors", i64(m.validation_errors)},
                {"out_of_order", i64(m.out_of_order)},
                {"time_jumps", i64(m.time_jumps)},
                {"odometry_overflow", i64(m.odometry_overflow)},
                {"cycles_without_camera", i64(m.cycles_without_camera)},
                {"cycles_without_contact", i64(m.cycles_without_contact)},
                {"checkpoints_written", i64(m.checkpoints_written)},
                {"checkpoint_errors", i64(m.checkpoint_errors)},
                {"checkpoints_superseded", i64(m.checkpoints_superseded)},
                {"lcm_publish_errors", i64(m.lcm_publish_errors)},
                {"lcm_receive_drops", i64(m.lcm_receive_drops)},
                {"input_gaps", i64(m.input_gaps)}};
  d.stats = {{"latency_last_ms", m.latency_last_ms},
             {"latency_p50_ms", m.latency_p50_ms},
             {"latency_p99_ms", m.latency_p99_ms},
             {"latency_max_ms", m.latency_max_ms}};
  bump(kStatus);
}

std::shared_ptr<const std::string> ViewerState::camera_jpeg() const {
  if (!have_frame_) return nullptr;
  if (!jpeg_tried_) {
    jpeg_tried_ = true;
    jpeg_ = frame_to_jpeg(frame_, params_.camera_max_width, params_.jpeg_quality);
  }
  return jpeg_;
}

json ViewerState::map_json() const {
  if (!have_map_) return nullptr;
  json ids = json::array(), xs = json::array(), ys = json::array(), dense = json::array();
  for (const experience_t& e : map_.experiences) {
    ids.push_back(e.id);
    xs.push_back(mm(e.x));
    ys.push_back(mm(e.y));
    dense.push_back(e.dense ? 1 : 0);
  }
  json links = json::array();  // flat: from, to, from, to, ...
  json revoked = json::array();  // per link: 1 where the back end revoked it
  int num_revoked = 0;
  for (const link_t& l : map_.links) {
    links.push_back(l.from_id);
    links.push_back(l.to_id);
    revoked.push_back(l.revoked ? 1 : 0);
    num_revoked += l.revoked ? 1 : 0;
  }
  return {{"utime", map_.utime},
          {"mode", mode_name(map_.mode)},
          {"current", map_.current_experience_id},
          {"num_experiences", map_.num_experiences},
          {"num_links", map_.num_links},
          {"num_revoked", num_revoked},
          {"num_dense", num_dense_},
          {"num_sparse", map_.num_experiences - num_dense_},
          {"id", std::move(ids)},
          {"x", std::move(xs)},
          {"y", std::move(ys)},
          {"dense", std::move(dense)},
          {"links", std::move(links)},
          {"revoked", std::move(revoked)}};
}

json ViewerState::pose_json() const {
  if (!have_pose_) return nullptr;
  return {{"utime", pose_.utime},
          {"x", mm(pose_.x)},
          {"y", mm(pose_.y)},
          {"theta", mm(pose_.theta)},
          {"experience_id", pose_.experience_id},
          {"template_id", pose_.template_id},
          {"localising", pose_.localisation == vita_pose_t::LOCALISATION_LOCALISING},
          {"mode", mode_name(pose_.mode)}};
}

json ViewerState::trail_json() const {
  json xy = json::array();  // flat: x, y, x, y, ...
  for (const Point& p : trail_) {
    xy.push_back(mm(p.x));
    xy.push_back(mm(p.y));
  }
  return {{"max_points", params_.trail_max_points}, {"xy", std::move(xy)}};
}

json ViewerState::camera_json() const {
  if (!have_frame_) return nullptr;
  // The page fetches the JPEG itself (/api/camera.jpg); `frame` (frames received so far) makes each
  // frame a new URL.
  return {{"utime", frame_.utime},
          {"width", frame_.width},
          {"height", frame_.height},
          {"pixelformat", frame_.pixelformat},
          {"frame", messages(channels::kCamera)}};
}

json ViewerState::whiskers_json() const {
  if (!have_whiskers_) return nullptr;
  json deflection = json::array(), theta = json::array();
  for (std::size_t i = 0; i < whiskers_.deflection.size(); ++i) {
    deflection.push_back(whiskers_.measured[i] ? json(mm(whiskers_.deflection[i])) : json(nullptr));
    theta.push_back(whiskers_.measured[i] ? json(mm(whiskers_.theta_max[i])) : json(nullptr));
  }
  int contacts = 0;
  for (bool c : whiskers_.contact) contacts += c ? 1 : 0;
  return {{"cycle", whiskers_.cycle},
          {"utime", whiskers_.utime},
          {"num_samples", whiskers_.num_samples},
          {"num_missing", whiskers_.num_missing},
          {"rows", kWhiskerRows},
          {"columns", kWhiskerColumns},
          {"num_contacts", contacts},
          {"contact", whiskers_.contact},
          {"deflection", std::move(deflection)},
          {"theta_max", std::move(theta)}};
}

json ViewerState::event_json() const {
  json counts = {{"same", event_counts_[0]}, {"new", event_counts_[1]}, {"relocalise", event_counts_[2]}};
  if (!have_event_) return {{"last", nullptr}, {"counts", std::move(counts)}};
  return {{"last",
           {{"utime", event_.utime},
            {"cycle", event_.cycle},
            {"type", event_type_name(event_.type)},
            {"from_id", event_.from_id},
            {"to_id", event_.to_id},
            {"template_id", event_.template_id},
            {"mode", mode_name(event_.mode)}}},
          {"counts", std::move(counts)}};
}

json ViewerState::match_json() const {
  if (!have_match_) return nullptr;
  return {{"utime", match_.utime},
          {"cycle", match_.cycle},
          {"template_id", match_.template_id},
          {"is_new", match_.is_new != 0},
          {"error", number(match_.error)},
          {"visual_error", number(match_.visual_error)},
          {"pfh_error", number(match_.pfh_error)},
          {"sda_error", number(match_.sda_error)},
          {"visual_shift", match_.visual_shift},
          {"num_templates", match_.num_templates},
          {"mode", mode_name(match_.mode)},
          {"visual_used", match_.visual_used != 0},
          {"tactile_used", match_.tactile_used != 0}};
}

json ViewerState::status_json() const {
  json list = json::array();
  for (const auto& [name, d] : daemons_) {
    json counters = json::array(), stats = json::array();
    for (const auto& [k, v] : d.counters) counters.push_back({k, number(v)});
    for (const auto& [k, v] : d.stats) stats.push_back({k, number(v)});
    list.push_back({{"name", name},
                    {"kind", d.kind},
                    {"state", state_name(d.state)},
                    {"colour", d.stale ? "stale" : state_name(d.state)},
                    {"stale", d.stale},
                    {"age_s", mm(static_cast<double>(now_utime_ - d.recv_utime) * 1e-6)},
                    {"message", d.message},
                    {"utime", d.utime},
                    {"counters", std::move(counters)},
                    {"stats", std::move(stats)}});
  }
  return list;
}

json ViewerState::meta_json() const {
  json per_channel = json::object();
  for (const auto& [channel, n] : messages_) per_channel[channel] = n;
  return {{"now", now_utime_},
          {"messages", std::move(per_channel)},
          {"decode_errors", decode_errors_},
          {"last_decode_error", last_decode_error_}};
}

json ViewerState::section(Section s) const {
  switch (s) {
    case kMap: return map_json();
    case kPose: return pose_json();
    case kTrail: return trail_json();
    case kCamera: return camera_json();
    case kWhiskers: return whiskers_json();
    case kEvent: return event_json();
    case kMatch: return match_json();
    case kStatus: return status_json();
    case kMeta: return meta_json();
    case kSections: break;
  }
  return nullptr;
}

namespace {
constexpr const char* kSectionNames[ViewerState::kSections] = {"map",   "pose",  "trail",  "camera", "whiskers",
                                                               "event", "match", "status", "meta"};
}  // namespace

json ViewerState::snapshot() const {
  json out = json::object();
  for (int s = 0; s < kSections; ++s) out[kSectionNames[s]] = section(static_cast<Section>(s));
  out["v"] = version_counter_;
  return out;
}

json ViewerState::delta(Cursor& cursor, int64_t now_us) const {
  json out = json::object();
  for (int s = 0; s < kSections; ++s) {
    const auto i = static_cast<std::size_t>(s);
    if (cursor.seen[i] == versions_[i]) continue;
    if (s == kTrail) {
      if (cursor.trail_sent_us != INT64_MIN && now_us - cursor.trail_sent_us < params_.trail_period_us) continue;
      cursor.trail_sent_us = now_us;
    }
    out[kSectionNames[s]] = section(static_cast<Section>(s));
    cursor.seen[i] = versions_[i];
  }
  if (!out.empty()) out["v"] = version_counter_;
  return out;
}

}  // namespace whiskeye::viewer
