#include "whiskeye/slamd/cycle_sync.h"

#include "whiskeye/common/utime.h"

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <iterator>
#include <utility>

namespace whiskeye::slamd {

CycleSynchroniser::CycleSynchroniser(const SyncParams& params) : params_(params) {}

namespace {

// a + b for b >= 0, without overflowing past INT64_MAX.
int64_t plus(int64_t a, int64_t b) { return a > INT64_MAX - b ? INT64_MAX : a + b; }
// a - b for b >= 0, without overflowing past INT64_MIN.
int64_t minus(int64_t a, int64_t b) { return a < INT64_MIN + b ? INT64_MIN : a - b; }

std::string seconds(int64_t us) {
  char text[32];
  std::snprintf(text, sizeof text, "%.3f", static_cast<double>(us) * 1e-6);
  return text;
}

std::string out_of_order(const char* name, int64_t utime, int64_t newest) {
  return std::string(name) + ": sample time " + seconds(newest - utime) + " s before the newest already taken (out of order)";
}

}  // namespace

void CycleSynchroniser::advance_data_time(int64_t utime) { data_time_ = std::max(data_time_, utime); }

bool CycleSynchroniser::confirms(Step& step, int input, int64_t utime) {
  const int64_t limit = seconds_to_utime(params_.max_jump_s);
  if (step.input >= 0 && step.input != input && std::llabs(utime - step.last) <= limit) {
    step.input = -1;
    return true;  // two inputs agree: the clock (or the recording) moved
  }
  if (step.input == input && utime > step.last && utime - step.last <= limit) {
    // The same input goes on from its new time (after a pause, or a clock step), and no other input
    // was heard meanwhile (any sample of theirs would have cancelled the step or confirmed it).
    step.last = utime;
    ++step.samples;
    if (step.samples >= kConfirmSamples && step.last - step.first >= kConfirmSpanUs) {
      step.input = -1;
      return true;
    }
    return false;
  }
  step = Step{input, utime, utime, 1};
  return false;
}

std::string CycleSynchroniser::check_jump(int input, int64_t utime, const char* name) {
  const int64_t limit = seconds_to_utime(params_.max_jump_s);
  if (data_time_ == INT64_MIN || utime <= plus(data_time_, limit)) {
    ahead_.input = behind_.input = -1;  // a sample in line: whatever stepped was one bad clock
    return {};
  }
  behind_.input = -1;
  if (confirms(ahead_, input, utime)) {
    ++counters_.jumps_followed;
    return {};
  }
  ++counters_.time_jumps;
  return std::string(name) + ": sample time " + seconds(utime - data_time_) +
         " s past the other inputs (dropped until another input, or this one alone over " +
         seconds(kConfirmSpanUs) + " s, confirm the jump)";
}

std::string CycleSynchroniser::check_step_back(int input, int64_t utime, int64_t own_newest, const char* name) {
  const int64_t limit = seconds_to_utime(params_.max_jump_s);
  if (data_time_ == INT64_MIN || plus(utime, limit) >= data_time_) {
    ++counters_.out_of_order;
    return out_of_order(name, utime, own_newest);
  }
  ahead_.input = -1;
  if (confirms(behind_, input, utime)) {
    ++counters_.jumps_followed;
    restart_time_line();
    return {};
  }
  ++counters_.time_jumps;
  return std::string(name) + ": sample time " + seconds(data_time_ - utime) +
         " s before the other inputs (a clock stepped back? dropped until another input, or this one "
         "alone over " + seconds(kConfirmSpanUs) + " s, confirm it)";
}

void CycleSynchroniser::restart_time_line() {
  restarted_ = flush();  // every pending cycle, with what arrived for it; the rest is the old time line
  frames_.clear();
  odometry_.clear();
  data_time_ = newest_camera_ = newest_odometry_ = consumed_until_ = INT64_MIN;
  ahead_ = behind_ = Step{};
  std::fill(std::begin(agreeing_), std::end(agreeing_), 0);
}

int64_t CycleSynchroniser::others_newest(int input) const {
  int64_t newest = INT64_MIN;
  if (input != 0) newest = std::max(newest, newest_camera_);
  if (input != 1) newest = std::max(newest, newest_odometry_);
  if (input != 2) newest = std::max(newest, last_cycle_end());
  return newest;
}

bool CycleSynchroniser::own_time_was_corrupt(int input, int64_t utime, int64_t own_newest) {
  const int64_t limit = seconds_to_utime(params_.max_jump_s);
  const int64_t others = others_newest(input);
  const bool outlying = others != INT64_MIN && own_newest > plus(others, limit);
  const bool agrees = others != INT64_MIN && std::llabs(utime - others) <= limit;
  if (!outlying || !agrees) {
    agreeing_[input] = 0;
    return false;
  }
  if (++agreeing_[input] < kConfirmSamples) return false;
  agreeing_[input] = 0;
  ++counters_.outliers_dropped;
  return true;
}

void CycleSynchroniser::recompute_data_time() {
  data_time_ = std::max({newest_camera_, newest_odometry_, last_cycle_end()});
}

std::string CycleSynchroniser::add_camera(CameraFrame frame) {
  if (frame.utime < newest_camera_) {
    if (own_time_was_corrupt(0, frame.utime, newest_camera_)) {
      std::erase_if(frames_, [&](const CameraFrame& f) { return f.utime > frame.utime; });
      newest_camera_ = frames_.empty() ? INT64_MIN : frames_.back().utime;
      recompute_data_time();
    } else if (std::string why = check_step_back(0, frame.utime, newest_camera_, "CAMERA"); !why.empty()) {
      return why;
    }
  }
  if (std::string why = check_jump(0, frame.utime, "CAMERA"); !why.empty()) return why;
  newest_camera_ = frame.utime;
  advance_data_time(frame.utime);
  frames_.push_back(std::move(frame));
  evict_frames();
  return {};
}

void CycleSynchroniser::evict_frames() {
  // The camera's own time line, not data time: another input's corrupt time (awaiting its undoing)
  // must not empty the buffer. A waiting cycle keeps the frames from camera_tolerance before its end
  // even when the camera's next frame leaps past it (a pause), and the newest frame always stays
  // (assemble() keeps one for a cycle with no newer).
  int64_t oldest_kept = minus(newest_camera_, seconds_to_utime(params_.camera_buffer_s));
  if (!pending_.empty()) {
    oldest_kept = std::min(oldest_kept, minus(pending_.front().utime_end, seconds_to_utime(params_.camera_tolerance_s)));
  }
  while (frames_.size() > 1 && frames_.front().utime < oldest_kept) frames_.pop_front();
  while (static_cast<int>(frames_.size()) > params_.camera_buffer) {
    frames_.pop_front();
    ++counters_.camera_overflow;
  }
}

std::string CycleSynchroniser::add_odometry(const odometry_t& odometry) {
  int64_t newest = std::max(newest_odometry_, consumed_until_);
  if (odometry.utime <= newest && odometry.utime > consumed_until_ &&
      own_time_was_corrupt(1, odometry.utime, newest_odometry_)) {
    std::erase_if(odometry_, [&](const odometry_t& o) { return o.utime >= odometry.utime; });
    newest_odometry_ = odometry_.empty() ? INT64_MIN : odometry_.back().utime;
    recompute_data_time();
    newest = std::max(newest_odometry_, consumed_until_);
  }
  if (odometry.utime <= newest) {
    if (std::string why = check_step_back(1, odometry.utime, newest, "ODOMETRY"); !why.empty()) return why;
  }
  if (std::string why = check_jump(1, odometry.utime, "ODOMETRY"); !why.empty()) return why;
  newest_odometry_ = odometry.utime;
  advance_data_time(odometry.utime);
  odometry_.push_back(odometry);
  // Without whisk cycles (whisking stopped, whiskerd down) nothing consumes odometry: bounded memory
  // over keeping every sample; the next cycle's path integration then starts at the oldest kept.
  if (static_cast<int>(odometry_.size()) > params_.odometry_buffer) {
    odometry_.pop_front();
    ++counters_.odometry_overflow;
  }
  return {};
}

std::string CycleSynchroniser::add_whisk_cycle(whisk_cycle_t cycle) {
  if (cycle.utime_end <= last_cycle_end() && cycle.utime_end > consumed_until_ &&
      own_time_was_corrupt(2, cycle.utime_end, last_cycle_end())) {
    std::erase_if(pending_, [&](const whisk_cycle_t& c) { return c.utime_end >= cycle.utime_end; });
    recompute_data_time();
  }
  if (cycle.utime_end <= last_cycle_end()) {
    if (std::string why = check_step_back(2, cycle.utime_end, last_cycle_end(), "WHISK_CYCLE"); !why.empty()) {
      return why;
    }
  }
  if (std::string why = check_jump(2, cycle.utime_end, "WHISK_CYCLE"); !why.empty()) return why;
  advance_data_time(cycle.utime_end);
  pending_.push_back(std::move(cycle));
  return {};
}

bool CycleSynchroniser::ready(const whisk_cycle_t& cycle) const {
  const int64_t end = cycle.utime_end;
  if (data_time_ >= plus(end, seconds_to_utime(params_.max_wait_s))) return true;
  const bool camera_settled = newest_camera_ >= plus(end, seconds_to_utime(params_.camera_tolerance_s));
  const bool odometry_settled = newest_odometry_ >= end;
  return camera_settled && odometry_settled;
}

SyncedCycle CycleSynchroniser::assemble(whisk_cycle_t&& cycle) {
  const int64_t end = cycle.utime_end;
  SyncedCycle out;
  out.whisk = std::move(cycle);
  const int64_t tolerance = seconds_to_utime(params_.camera_tolerance_s);
  const CameraFrame* best = nullptr;
  for (const auto& f : frames_) {
    const int64_t d = std::llabs(f.utime - end);
    if (d <= tolerance && (best == nullptr || d < std::llabs(best->utime - end))) best = &f;
  }
  if (best != nullptr) {
    out.image = *best;
  } else {
    ++counters_.cycles_without_camera;
  }
  while (!odometry_.empty() && odometry_.front().utime <= end) {
    out.odometry.push_back(odometry_.front());
    odometry_.pop_front();
  }
  // Frames at or before this cycle's end cannot be nearest to a later cycle's end than a newer one
  // unless no newer frame exists; keep the newest of them for that case.
  while (frames_.size() > 1 && frames_[1].utime <= end) frames_.pop_front();
  consumed_until_ = end;
  return out;
}

std::vector<SyncedCycle> CycleSynchroniser::take_ready() {
  std::vector<SyncedCycle> out = std::exchange(restarted_, {});
  while (!pending_.empty() && ready(pending_.front())) {
    out.push_back(assemble(std::move(pending_.front())));
    pending_.pop_front();
  }
  return out;
}

std::vector<SyncedCycle> CycleSynchroniser::flush() {
  std::vector<SyncedCycle> out = std::exchange(restarted_, {});
  while (!pending_.empty()) {
    out.push_back(assemble(std::move(pending_.front())));
    pending_.pop_front();
  }
  return out;
}

}  // namespace whiskeye::slamd
