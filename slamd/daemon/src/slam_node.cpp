// The slamd node (slam_node.h): messages in, cycles through the core, messages out.
#include "whiskeye/slamd/slam_node.h"

#include "message_checks.h"
#include "whiskeye/slamd/mjpeg_decode.h"
#include "whiskeye/slamd/wire_conversion.h"

#include "whiskeye/slam/visual_template.h"

#include "whiskeye/common/clock.h"
#include "whiskeye/common/se2.h"
#include "whiskeye/common/utime.h"

#include <whiskeye/driver_status_t.hpp>
#include <whiskeye/vita_pose_t.hpp>

#include <algorithm>

namespace whiskeye::slamd {

SlamNode::SlamNode(Bus& in, Bus& out, std::unique_ptr<slam::VitaSlam> slam, const NodeParams& params,
                   DecodeErrors& decode_errors)
    : out_(out),
      slam_(std::move(slam)),
      params_(params),
      decode_errors_(decode_errors),
      sync_(params.sync),
      log_clock_([] { return monotonic_us(); }) {
  slam_->set_frame_decoder(mjpeg_decoder());  // MJPEG frames are decoded here, at the daemon's edge
  // Undecodable messages through the throttle: the first of a channel, then a line per 10 s with a count.
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
    // Decoded into a processed cycle's message when there is one: its vectors' storage is reused.
    whisk_cycle_t msg;
    if (!spare_cycles_.empty()) {
      msg = std::move(spare_cycles_.back());
      spare_cycles_.pop_back();
    }
    std::string reason = whisk_cycle_size_error(data);
    if (reason.empty()) {
      // Decodable, but counts outside the contract: rejected before the decoder allocates for them.
      if (std::string bad = whisk_cycle_contract_error(data); !bad.empty()) return reject(kWhisk, bad);
      decode_message(data, msg, &reason);  // sets the reason when it fails
    }
    if (!reason.empty()) return decode_errors_.record(info.channel, reason);
    on_whisk_cycle(std::move(msg));
  });
}

void SlamNode::reject(Input input, const std::string& what) {
  ++counters_.validation_errors;
  log_burst(input, "rejected " + what + " (" + std::to_string(counters_.validation_errors) + " rejected so far)");
}

void SlamNode::reject(Input input, int64_t seq, const std::string& what) {
  gaps_[input].arrived(seq);
  reject(input, what);
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
  if (!err.empty()) return reject(kCamera, frame.seq, err);
  if (info.data_owner) {
    frame.owner = info.data_owner;  // the bytes outlive this call: keep a view
  } else {
    own_pixels(frame);
  }
  const int64_t seq = frame.seq;
  const int64_t overflow_before = sync_.counters().camera_overflow;
  if (const std::string why = sync_.add_camera(std::move(frame)); !why.empty()) return reject(kCamera, seq, why);
  if (sync_.counters().camera_overflow != overflow_before) {
    warn("camera_buffer", "camera_buffer (" + std::to_string(params_.sync.camera_buffer) +
                              " frames) is too small for camera_buffer_s at the camera's rate: dropped frames a "
                              "whisk cycle may still use (it then goes without vision); raise camera_buffer");
  }
  accepted(kCamera);
  sequence(kCamera, seq);
  process(sync_.take_ready());
}

void SlamNode::on_whisk_cycle(whisk_cycle_t msg) {
  const std::string err = check_whisk_cycle(msg);
  if (!err.empty()) return reject(kWhisk, msg.cycle, err);
  const int64_t seq = msg.cycle;
  if (const std::string why = sync_.add_whisk_cycle(std::move(msg)); !why.empty()) return reject(kWhisk, seq, why);
  accepted(kWhisk);
  sequence(kWhisk, seq);
  process(sync_.take_ready());
}

void SlamNode::on_odometry(const odometry_t& msg) {
  const std::string err = check_odometry(msg);
  if (!err.empty()) return reject(kOdometry, msg.seq, err);
  // A dropped sample is not dead-reckoned either (a pose back in time, or an hour ahead).
  const int64_t overflow_before = sync_.counters().odometry_overflow;
  if (const std::string why = sync_.add_odometry(msg); !why.empty()) return reject(kOdometry, msg.seq, why);
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
  constexpr std::size_t kSpareCycles = 4;
  for (auto& c : cycles) {
    process_one(c);
    if (spare_cycles_.size() < kSpareCycles) spare_cycles_.push_back(std::move(c.whisk));
  }
}

void SlamNode::process_one(const SyncedCycle& cycle) {
  const int64_t t0 = clock_ ? clock_() : 0;
  to_core(cycle.whisk, whisk_input_);
  const slam::WhiskCycleInput& whisk = whisk_input_;
  const bool contact = has_contact(cycle.whisk);
  // The frame's pixels the SLAM reads (the rows down to the crop's bottom; none in tactile mode),
  // and only those: a replay reads no more of them from the log.
  slam::ImageView view{};
  if (cycle.image && slam::uses_visual(slam_->params().mode)) {
    view = slam::visual_rows(to_core(*cycle.image), slam_->params().visual);
    if (read_pixels_) read_pixels_(cycle.image->owner, view.data);
  }
  slam::CycleInput input;
  input.utime = cycle.whisk.utime_end;
  input.cycle = cycle.whisk.cycle;
  input.image = cycle.image ? &view : nullptr;
  input.whisk = &whisk;
  input.odometry.reserve(cycle.odometry.size());
  for (const auto& o : cycle.odometry) input.odometry.push_back(to_core(o));

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
  const slam::Mode mode = slam_->params().mode;
  publish(out_, params_.channels.event, event_message(r, input.utime, input.cycle, mode));
  publish(out_, params_.channels.match, match_message(r, input.utime, input.cycle, mode));

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
  publish(out_, params_.channels.map, map_message(slam_->map(), utime, slam_->params().mode));
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
