// Sequence and jump checks on the base's odometry, and re-anchoring after a reset.
#include "whiskeye/based/tracker.h"

#include <algorithm>
#include <cmath>
#include <sstream>

namespace whiskeye::based {

const char* to_string(SampleKind kind) {
  switch (kind) {
    case SampleKind::kFirst: return "first";
    case SampleKind::kNew: return "new";
    case SampleKind::kRepeated: return "repeated_seq";
    case SampleKind::kSeqBackwards: return "seq_backwards";
    case SampleKind::kJump: return "odometry_jump";
  }
  return "?";
}

OdometrySample OdometryTracker::published_from(const OdometrySample& raw) const {
  OdometrySample out = raw;
  const Pose2 p = compose(offset_, Pose2{raw.x, raw.y, raw.theta});  // also wraps theta
  out.x = p.x;
  out.y = p.y;
  out.theta = p.theta;
  return out;
}

TrackResult OdometryTracker::track(const OdometrySample& raw) {
  TrackResult r;
  if (!have_last_) {
    r.kind = SampleKind::kFirst;
  } else if (raw.seq == last_raw_.seq) {
    r.kind = SampleKind::kRepeated;
    r.detail = "seq " + std::to_string(raw.seq) + " repeated";
    return r;
  } else if (raw.seq < last_raw_.seq) {
    r.kind = SampleKind::kSeqBackwards;
    r.detail = "seq went back from " + std::to_string(last_raw_.seq) + " to " + std::to_string(raw.seq);
  } else {
    const double dt = std::max(0.0, static_cast<double>(raw.mono_us - last_raw_.mono_us) * 1e-6);
    const double speed = std::max(std::hypot(last_raw_.vx, last_raw_.vy), std::hypot(raw.vx, raw.vy));
    const double turn = std::max(std::abs(last_raw_.omega), std::abs(raw.omega));
    const double moved = std::hypot(raw.x - last_raw_.x, raw.y - last_raw_.y);
    const double turned = std::abs(angle_diff(raw.theta, last_raw_.theta));
    const double max_move = params_.jump_velocity_factor * speed * dt + params_.jump_margin_m;
    const double max_turn = params_.jump_velocity_factor * turn * dt + params_.jump_margin_rad;
    if (moved > max_move || turned > max_turn) {
      r.kind = SampleKind::kJump;
      std::ostringstream s;
      s.precision(3);
      s << "odometry jumped " << moved << " m / " << turned << " rad in " << dt
        << " s (velocity explains " << max_move << " m / " << max_turn << " rad) at seq " << raw.seq;
      r.detail = s.str();
    } else {
      r.kind = SampleKind::kNew;
    }
  }

  if ((r.kind == SampleKind::kSeqBackwards || r.kind == SampleKind::kJump) &&
      params_.continuous_after_reset) {
    // Continue from where the last published pose would be now, moving at the last velocity: the
    // base's new origin is arbitrary, the motion since the last sample is the best guess we have.
    const double dt = std::clamp(static_cast<double>(raw.mono_us - last_published_.mono_us) * 1e-6, 0.0, 1.0);
    const Pose2 predicted =
        integrate_body_velocity(Pose2{last_published_.x, last_published_.y, last_published_.theta},
                                last_published_.vx, last_published_.vy, last_published_.omega, dt);
    offset_ = compose(predicted, inverse(Pose2{raw.x, raw.y, raw.theta}));
  }
  have_last_ = true;
  last_raw_ = raw;
  last_published_ = published_from(raw);
  r.publish = last_published_;
  return r;
}

}  // namespace whiskeye::based
