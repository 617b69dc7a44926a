// Classifies each valid odometry sample against the previous one: a new sample, a repeat of the
// same seq (the base has not produced a new one), or a reset of the base's odometry (seq going
// backwards, or a position jump that the reported velocities cannot explain). After a reset the
// published pose can be kept continuous by re-anchoring on the velocity-predicted pose.
// Pure: time comes in with the samples. Intervals (the jump check's dt, the re-anchoring
// prediction, staleness) use the samples' monotonic mono_us; their wall-clock utime is only passed
// through to what is published.
#pragma once

#include "whiskeye/based/params.h"
#include "whiskeye/based/protocol.h"
#include "whiskeye/common/se2.h"

#include <optional>
#include <string>

namespace whiskeye::based {

enum class SampleKind {
  kFirst,         // first sample since start: published
  kNew,           // seq advanced and the motion is plausible: published
  kRepeated,      // same seq as the last sample: not published
  kSeqBackwards,  // seq went backwards: the base restarted its odometry; published (re-anchored)
  kJump,          // position/heading jump beyond what velocity explains; published (re-anchored)
};

const char* to_string(SampleKind kind);

struct TrackResult {
  SampleKind kind = SampleKind::kFirst;
  std::optional<OdometrySample> publish;  // what to publish (pose re-anchored, theta wrapped)
  std::string detail;                     // why, for a repeat or a reset
};

class OdometryTracker {
 public:
  explicit OdometryTracker(const OdometryParams& params) : params_(params) {}

  // `raw.utime` and `raw.mono_us` must be set. Samples must come in reception order.
  TrackResult track(const OdometrySample& raw);

  // utime / mono_us of the last sample with a new seq (0 before the first).
  int64_t last_new_utime() const { return have_last_ ? last_raw_.utime : 0; }
  int64_t last_new_mono_us() const { return have_last_ ? last_raw_.mono_us : 0; }
  // No new seq for more than stale_after_s at monotonic time now_mono_us (false before the first).
  bool stale(int64_t now_mono_us) const {
    return have_last_ && static_cast<double>(now_mono_us - last_raw_.mono_us) * 1e-6 > params_.stale_after_s;
  }
  // The transform from the base's odometry frame to the published frame (identity until a reset).
  const Pose2& offset() const { return offset_; }

 private:
  OdometrySample published_from(const OdometrySample& raw) const;

  OdometryParams params_;
  bool have_last_ = false;
  OdometrySample last_raw_;
  OdometrySample last_published_;
  Pose2 offset_;
};

}  // namespace whiskeye::based
