#include "whiskeye/slamd/slam_node.h"

#include "whiskeye/slamd/mjpeg_decode.h"

#include "whiskeye/common/clock.h"
#include "whiskeye/common/robot_geometry.h"
#include "whiskeye/common/se2.h"
#include "whiskeye/common/utime.h"

#include <whiskeye/template_match_t.hpp>
#include <whiskeye/vita_event_t.hpp>
#include <whiskeye/vita_map_t.hpp>
#include <whiskeye/vita_pose_t.hpp>
#include <whiskeye/driver_status_t.hpp>

#include <algorithm>
#include <cmath>

namespace whiskeye::slamd {

void load(const ParamNode& node, NodeParams& p) {
  node.get("camera_tolerance_s", p.sync.camera_tolerance_s, 0.0, 2.0);
  node.get("max_wait_s", p.sync.max_wait_s, 0.05, 30.0);
  node.get("camera_buffer", p.sync.camera_buffer, 1, 1000);
  node.get("max_jump_s", p.sync.max_jump_s, 1.0, 86400.0);
  node.get("odometry_buffer", p.sync.odometry_buffer, 100, 10000000);
  node.get("map_period_s", p.map_period_s, 0.0, 3600.0);
  // The same key names as whiskerd's lcm.channel_* for the same channel (channel_cycle).
  node.get("channel_cycle", p.channels.cycle);
  node.get("channel_camera", p.channels.camera);
  node.get("channel_odometry", p.channels.odometry);
  node.get("channel_pose", p.channels.pose);
  node.get("channel_event", p.channels.event);
  node.get("channel_match", p.channels.match);
  node.get("channel_map", p.channels.map);
  node.get("channel_status", p.channels.status);
}

namespace {

constexpr int64_t kMaxCycleUs = 60'000'000;  // a whisk cycle's duration: far beyond any
// Plausible readings (docs/lcm-channels.md): whisker angles are within a turn either way, calibrated
// deflections within -1..1 (half again for calibration slack); odometry positions within 100 km.
constexpr double kMaxWhiskerAngle = kPi;
constexpr double kMaxDeflection = 1.5;
constexpr double kMaxOdometryPosition = 1e5;

int8_t mode_code(slam::Mode mode) {
  switch (mode) {
    case slam::Mode::Visual: return vita_pose_t::MODE_VISUAL;
    case slam::Mode::Tactile: return vita_pose_t::MODE_TACTILE;
    case slam::Mode::Vita: return vita_pose_t::MODE_VITA;
  }
  return vita_pose_t::MODE_VITA;
}

int8_t event_code(slam::EventType type) {
  switch (type) {
    case slam::EventType::SameExperience: return vita_event_t::SAME_EXPERIENCE;
    case slam::EventType::NewExperience: return vita_event_t::NEW_EXPERIENCE;
    case slam::EventType::Relocalise: return vita_event_t::RELOCALISE;
  }
  return vita_event_t::SAME_EXPERIENCE;
}

int8_t localisation_code(bool localising) {
  return localising ? vita_pose_t::LOCALISATION_LOCALISING : vita_pose_t::LOCALISATION_TRACKING;
}

bool finite(double v) { return std::isfinite(v); }

std::string check_whisk_cycle(const whisk_cycle_t& m) {
  if (std::string bad = sample_time_error("WHISK_CYCLE", m.utime_start); !bad.empty()) return bad;
  if (std::string bad = sample_time_error("WHISK_CYCLE", m.utime_end); !bad.empty()) return bad;
  if (std::string bad = whisk_cycle_counts_error(m.num_whiskers, m.num_samples); !bad.empty()) return bad;
  if (m.utime_end < m.utime_start) return "WHISK_CYCLE: utime_end before utime_start";
  if (m.utime_end - m.utime_start > kMaxCycleUs) {
    return "WHISK_CYCLE: lasts " + std::to_string((m.utime_end - m.utime_start) / 1000) + " ms (more than 60 s)";
  }
  int missing_samples = 0;
  for (int s = 0; s < m.num_samples; ++s) {
    // The words of an error are built only for an error (a valid cycle is ~5,000 samples × 24).
    const auto at = [s] { return " at sample " + std::to_string(s); };
    // Within the cycle (so no difference of sample times can overflow), in order.
    if (m.sample_utime[s] < m.utime_start || m.sample_utime[s] > m.utime_end) {
      return "WHISK_CYCLE: sample time " + std::to_string(m.sample_utime[s]) + at() + " is outside the cycle";
    }
    if (s > 0 && m.sample_utime[s] < m.sample_utime[s - 1]) return "WHISK_CYCLE: sample times go backwards" + at();
    if (m.sample_valid[s] != 0 && m.sample_valid[s] != 1) {
      return "WHISK_CYCLE: sample_valid " + std::to_string(m.sample_valid[s]) + at() + " (0 or 1)";
    }
    if (!m.sample_valid[s]) {
      ++missing_samples;
      continue;
    }
    for (int w = 0; w < kNumWhiskers; ++w) {
      const double theta = m.theta[s][w], dx = m.deflection_x[s][w], dy = m.deflection_y[s][w];
      // A whisker not measured in a sample is NaN in all three values (docs/lcm-channels.md).
      if (std::isnan(theta) && std::isnan(dx) && std::isnan(dy)) continue;
      const auto whisker = [&at, w] { return at() + ", whisker " + std::to_string(w); };
      if (!finite(theta) || !finite(dx) || !finite(dy)) return "WHISK_CYCLE: non-finite value" + whisker();
      if (std::abs(theta) > kMaxWhiskerAngle) {
        return "WHISK_CYCLE: theta " + std::to_string(theta) + " rad" + whisker() + " (beyond ±pi)";
      }
      if (std::abs(dx) > kMaxDeflection || std::abs(dy) > kMaxDeflection) {
        return "WHISK_CYCLE: deflection (" + std::to_string(dx) + ", " + std::to_string(dy) + ")" + whisker() +
               " (calibrated -1..1)";
      }
    }
  }
  if (m.num_missing != missing_samples) {
    return "WHISK_CYCLE: num_missing " + std::to_string(m.num_missing) + " but " + std::to_string(missing_samples) +
           " samples are marked lost";
  }
  return "";
}

std::string check_odometry(const odometry_t& m) {
  if (std::string bad = sample_time_error("ODOMETRY", m.utime); !bad.empty()) return bad;
  for (double v : {m.x, m.y, m.theta, m.vx, m.vy, m.omega}) {
    if (!finite(v)) return "ODOMETRY: non-finite value";
  }
  if (std::abs(m.x) > kMaxOdometryPosition || std::abs(m.y) > kMaxOdometryPosition) {
    return "ODOMETRY: position (" + std::to_string(m.x) + ", " + std::to_string(m.y) + ") m is beyond 100 km";
  }
  if (std::abs(m.theta) > kPi + 1e-9) {
    return "ODOMETRY: theta " + std::to_string(m.theta) + " rad is not in (-pi, pi]";
  }
  if (std::hypot(m.vx, m.vy) > slam::kMaxSpeed || std::abs(m.omega) > slam::kMaxTurnRate) {
    return "ODOMETRY: velocity (" + std::to_string(m.vx) + ", " + std::to_string(m.vy) + " m/s, " +
           std::to_string(m.omega) + " rad/s) beyond any base's";
  }
  return "";
}

// Contact in a measured sample (a lost sample's flags say nothing).
bool has_contact(const whisk_cycle_t& m) {
  for (std::size_t s = 0; s < m.contact.size(); ++s) {
    if (!m.sample_valid[s]) continue;
    for (int8_t c : m.contact[s]) {
      if (c) return true;
    }
  }
  return false;
}

}  // namespace

slam::WhiskCycleInput to_core(const whisk_cycle_t& m) {
  slam::WhiskCycleInput in;
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
  return in;
}

SlamNode::SlamNode(Bus& in, Bus& out, std::unique_ptr<slam::VitaSlam> slam, const NodeParams& params,
                   DecodeErrors& decode_errors)
    : out_(out),
      slam_(std::move(slam)),
      params_(params),
      decode_errors_(decode_errors),
      sync_(params.sync),
      log_clock_([] { return monotonic_us(); }) {
  slam_->set_frame_decoder(mjpeg_decoder());  // MJPEG frames are decoded here, at the daemon's edge
  // 2,000 undecodable messages were 2,000 lines: the first per channel, then one per 10 s with a count.
  decode_errors_.set_callback([this](const std::string& channel, const std::string& reason) {
    warn("decode " + channel, channel + ": " + reason);
  });
  // Camera frames are the bulk of the input: decoded as views (no pixel copy), see on_camera().
  in.subscribe_raw(params_.channels.camera, [this](std::span<const uint8_t> data, const MessageInfo& info) { on_camera(data, info); });
  subscribe<odometry_t>(in, params_.channels.odometry, [this](const odometry_t& m) { on_odometry(m); }, decode_errors_);
  // The generated decoder sizes its arrays from the message's counts before it checks them against
  // the message's length (a negative count throws, a huge one allocates gigabytes): check them first,
  // against the length, then against the contract.
  in.subscribe_raw(params_.channels.cycle, [this](std::span<const uint8_t> data, const MessageInfo& info) {
    whisk_cycle_t msg;
    std::string reason = whisk_cycle_size_error(data);
    if (reason.empty()) {
      // Decodable, but counts outside the contract: rejected before the decoder allocates for them.
      if (std::string bad = whisk_cycle_contract_error(data); !bad.empty()) return reject(kWhisk, bad);
      decode_message(data, msg, &reason);  // sets the reason when it fails
    }
    if (!reason.empty()) return decode_errors_.record(info.channel, reason);
    on_whisk_cycle(msg);
  });
}

void SlamNode::reject(Input input, const std::string& what) {
  ++counters_.validation_errors;
  log_burst(input, "rejected " + what + " (" + std::to_string(counters_.validation_errors) + " rejected so far)");
}

void SlamNode::log_burst(Input input, const std::string& line) {
  // Per input, so a broken sender is logged at the start of each burst even while the other inputs
  // are fine, and then rate-limited, so a flood of bad messages cannot flood the journal.
  const std::string key = "input " + std::to_string(static_cast<int>(input));
  if (rejects_in_burst_[input]++ == 0) {
    const std::string first = throttle_.force(key, line, log_clock_());  // starts the key's period
    if (logger_) logger_(first);
    return;
  }
  warn(key, line);
}

void SlamNode::warn(const std::string& key, const std::string& line) {
  if (!logger_) return;
  if (auto admitted = throttle_.admit(key, line, log_clock_())) logger_(*admitted);
}

void SlamNode::sequence(Input input, int64_t seq) {
  const int64_t missing = gaps_[input].add(seq);
  if (missing == 0) return;
  counters_.input_gaps = add_count_saturating(counters_.input_gaps, missing);  // a corrupt seq may claim 2^63
  static constexpr const char* kWhat[] = {"CAMERA: frames", "ODOMETRY: samples", "WHISK_CYCLE: cycles"};
  warn(std::string("gap-") + kWhat[input],
       std::string(kWhat[input]) + " missing by the sequence numbers: " + std::to_string(missing) + " before " +
           std::to_string(seq) + " (lost on the way: LCM, the network or a recording)");
}

void SlamNode::on_camera(std::span<const uint8_t> data, const MessageInfo& info) {
  CameraFrame frame;
  std::string reason;
  if (!decode_camera_frame(data, frame, &reason)) return decode_errors_.record(info.channel, reason);
  const std::string err = camera_frame_error(frame);
  if (!err.empty()) return reject(kCamera, err);
  if (info.data_owner) {
    frame.owner = info.data_owner;  // the bytes outlive this call: keep a view
  } else {
    own_pixels(frame);
  }
  const int64_t seq = frame.seq;
  if (const std::string why = sync_.add_camera(std::move(frame)); !why.empty()) return reject(kCamera, why);
  accepted(kCamera);
  sequence(kCamera, seq);
  process(sync_.take_ready());
}

void SlamNode::on_whisk_cycle(const whisk_cycle_t& msg) {
  const std::string err = check_whisk_cycle(msg);
  if (!err.empty()) return reject(kWhisk, err);
  if (const std::string why = sync_.add_whisk_cycle(msg); !why.empty()) return reject(kWhisk, why);
  accepted(kWhisk);
  sequence(kWhisk, msg.cycle);
  process(sync_.take_ready());
}

void SlamNode::on_odometry(const odometry_t& msg) {
  const std::string err = check_odometry(msg);
  if (!err.empty()) return reject(kOdometry, err);
  // A dropped sample is not dead-reckoned either (a pose back in time, or an hour ahead).
  const int64_t overflow_before = sync_.counters().odometry_overflow;
  if (const std::string why = sync_.add_odometry(msg); !why.empty()) return reject(kOdometry, why);
  accepted(kOdometry);
  sequence(kOdometry, msg.seq);
  // Logged at the first dropped sample of each stretch without whisk cycles, not at every one.
  if (sync_.counters().odometry_overflow != overflow_before && !odometry_overflowing_) {
    odometry_overflowing_ = true;
    if (logger_) {
      logger_("no whisk cycle for " + std::to_string(params_.sync.odometry_buffer) +
              " odometry samples: dropping the oldest (their motion is lost to the map) until whisking resumes");
    }
  }
  process(sync_.take_ready());
  if (!have_cycle_) return;
  // Dead-reckon from the last cycle's end with the base's own odometry pose.
  const Pose2 offset = between(odom_at_last_cycle_, Pose2{msg.x, msg.y, msg.theta});
  const Pose2 pose = slam_->dead_reckon(offset);
  vita_pose_t out{};
  out.utime = msg.utime;
  out.x = pose.x;
  out.y = pose.y;
  out.theta = pose.theta;
  out.experience_id = slam_->map().current_id();
  out.template_id = last_template_id_;
  out.mode = mode_code(slam_->params().mode);
  slam_->pose_cells().best(out.pose_cell_x, out.pose_cell_y, out.pose_cell_theta);
  out.localisation = localisation_code(slam_->localiser().localising());
  publish(out_, params_.channels.pose, out);
}

void SlamNode::process(std::vector<SyncedCycle> cycles) {
  for (const auto& c : cycles) process_one(c);
}

void SlamNode::process_one(const SyncedCycle& cycle) {
  const int64_t t0 = clock_ ? clock_() : 0;
  const slam::WhiskCycleInput whisk = to_core(cycle.whisk);
  const bool contact = has_contact(cycle.whisk);
  slam::ImageView view{};
  if (cycle.image) {
    const CameraFrame& im = *cycle.image;
    view = slam::ImageView{im.utime, im.width, im.height, im.row_stride, static_cast<uint32_t>(im.pixelformat), im.data};
  }
  slam::CycleInput input;
  input.utime = cycle.whisk.utime_end;
  input.cycle = cycle.whisk.cycle;
  input.image = cycle.image ? &view : nullptr;
  input.whisk = &whisk;
  input.odometry.reserve(cycle.odometry.size());
  for (const auto& o : cycle.odometry) input.odometry.push_back({o.utime, o.vx, o.vy, o.omega});

  const slam::CycleResult r = slam_->process_cycle(input);
  ++counters_.cycles;
  odometry_overflowing_ = false;  // the cycle took its odometry out of the buffer
  // A frame the core could not use (an MJPEG frame that does not decode, a crop outside it): the
  // cycle went on without vision, and the frame counts as rejected, with the reason logged.
  if (!r.image_warning.empty()) {
    reject(kFrameInCycle, "CAMERA frame for cycle " + std::to_string(cycle.whisk.cycle) + ": " + r.image_warning);
  } else if (cycle.image) {
    accepted(kFrameInCycle);
  }
  // A whisk cycle without one valid sample is not a bad message (every sensor of the head was out):
  // it went on without touch, counted in cycles_without_contact, and logged like a rejection.
  if (!r.whisk_warning.empty()) {
    log_burst(kWhiskInCycle, r.whisk_warning + ": mapped without touch");
  } else {
    accepted(kWhiskInCycle);
  }
  if (!cycle.image) ++counters_.cycles_without_camera;
  if (!contact) ++counters_.cycles_without_contact;
  if (!cycle.odometry.empty()) {
    const odometry_t& last = cycle.odometry.back();
    odom_at_last_cycle_ = Pose2{last.x, last.y, last.theta};
  }
  have_cycle_ = true;
  last_template_id_ = r.match.template_id;
  const int8_t mode = mode_code(slam_->params().mode);

  vita_event_t ev{};
  ev.utime = input.utime;
  ev.cycle = input.cycle;
  ev.type = event_code(r.event.type);
  ev.from_id = r.event.from_id;
  ev.to_id = r.event.to_id;
  ev.template_id = r.match.template_id;
  ev.mode = mode;
  ev.localisation = localisation_code(r.localising);
  publish(out_, params_.channels.event, ev);

  template_match_t m{};
  m.utime = input.utime;
  m.cycle = input.cycle;
  m.template_id = r.match.template_id;
  m.is_new = r.match.is_new;
  m.error = r.match.error;
  m.visual_error = r.match.visual_error;
  m.pfh_error = r.match.pfh_error;
  m.sda_error = r.match.sda_error;
  m.visual_shift = r.match.visual_shift;
  m.num_templates = r.num_templates;
  m.mode = mode;
  m.visual_used = r.match.visual_used;
  m.tactile_used = r.match.tactile_used;
  publish(out_, params_.channels.match, m);

  if (r.event.type != slam::EventType::SameExperience || r.match.is_new) map_dirty_ = true;
  // (A cycle before the last map's time: the clock was stepped back and followed; not throttled.)
  if (map_dirty_ && (last_map_utime_ == INT64_MIN || input.utime < last_map_utime_ ||
                     input.utime - last_map_utime_ >= seconds_to_utime(params_.map_period_s))) {
    publish_map(input.utime);
  }
  if (clock_) {
    latencies_ms_.push_back(static_cast<double>(clock_() - t0) / 1000.0);
    if (latencies_ms_.size() > 1000) latencies_ms_.pop_front();
  }
  if (cycle_hook_) cycle_hook_(r);
}

void SlamNode::publish_map(int64_t utime) {
  const auto& map = slam_->map();
  vita_map_t msg{};
  msg.utime = utime;
  msg.mode = mode_code(slam_->params().mode);
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
    msg.links.push_back(x);
  }
  msg.num_links = static_cast<int32_t>(msg.links.size());
  publish(out_, params_.channels.map, msg);
  last_map_utime_ = utime;
  map_dirty_ = false;
}

void SlamNode::flush() {
  process(sync_.flush());
  if (have_cycle_) publish_map(sync_.data_time());
}

slam_status_t SlamNode::status(int64_t utime, int64_t window_now_us) {
  slam_status_t s{};
  s.utime = utime;
  s.mode = mode_code(slam_->params().mode);
  s.cycles = counters_.cycles;
  s.num_templates = slam_->templates().size();
  s.num_experiences = static_cast<int32_t>(slam_->map().experiences().size());
  s.num_links = static_cast<int32_t>(slam_->map().links().size());
  if (!latencies_ms_.empty()) {
    std::vector<double> sorted(latencies_ms_.begin(), latencies_ms_.end());
    std::sort(sorted.begin(), sorted.end());
    const auto at = [&](double q) { return sorted[static_cast<std::size_t>(q * static_cast<double>(sorted.size() - 1))]; };
    s.latency_last_ms = latencies_ms_.back();
    s.latency_p50_ms = at(0.5);
    s.latency_p99_ms = at(0.99);
    s.latency_max_ms = sorted.back();
  }
  s.decode_errors = decode_errors_.total();
  s.validation_errors = counters_.validation_errors;
  const SyncCounters& sync = sync_.counters();
  s.out_of_order = sync.out_of_order;
  s.time_jumps = sync.time_jumps;
  s.outliers_dropped = sync.outliers_dropped;
  s.jumps_followed = sync.jumps_followed;
  s.odometry_overflow = sync.odometry_overflow;
  s.cycles_without_camera = counters_.cycles_without_camera;
  s.cycles_without_contact = counters_.cycles_without_contact;
  s.input_gaps = counters_.input_gaps;
  const slam::Localiser& loc = slam_->localiser();
  s.localisation = localisation_code(loc.localising());
  s.hypotheses = loc.hypotheses();
  s.kidnaps_detected = loc.kidnaps_detected();
  s.localisations = loc.localisations();
  constexpr int64_t kWindow = 10 * kUtimePerSecond;
  const bool rejecting =
      recent_errors_.changed_within(s.decode_errors + s.validation_errors, window_now_us, kWindow);
  const bool blind = slam::uses_visual(slam_->params().mode) &&
                     recent_without_camera_.changed_within(s.cycles_without_camera, window_now_us, kWindow);
  s.state = rejecting || blind || loc.localising() ? driver_status_t::STATE_DEGRADED : driver_status_t::STATE_OK;
  if (rejecting) s.message = "rejected input in the last 10 s: see decode_errors / validation_errors";
  if (blind) s.message += std::string(s.message.empty() ? "" : "; ") + "cycles without a camera frame in the last 10 s";
  if (loc.localising()) {
    s.message += std::string(s.message.empty() ? "" : "; ") + "localising: where the robot is is unknown (" +
                 std::to_string(loc.hypotheses()) + " candidate places)";
  }
  return s;
}

bool SlamNode::Recent::changed_within(int64_t now_value, int64_t utime, int64_t window_us) {
  if (now_value != value) {
    value = now_value;
    changed_at = utime;
  }
  // A window clock that went back (a replayed log across a clock step): the change counts from now,
  // instead of for as long as the step.
  if (changed_at != INT64_MIN && utime < changed_at) changed_at = utime;
  return changed_at != INT64_MIN && utime - changed_at < window_us;
}

void SlamNode::publish_status(int64_t utime) { publish(out_, params_.channels.status, status(utime)); }

}  // namespace whiskeye::slamd
