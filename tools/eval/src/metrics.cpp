// ATE, LEM, ExM and EnM as specified in ../shared/design/metrics.md (see metrics.h for the contract).
#include "whiskeye/eval/metrics.h"

#include "whiskeye/common/utime.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <span>
#include <stdexcept>
#include <utility>

namespace whiskeye::eval {

const MapExperience* ExperienceMap::find(int32_t id) const {
  for (const MapExperience& e : experiences) {
    if (e.id == id) return &e;
  }
  return nullptr;
}

std::size_t ExperienceMap::revoked_links() const {
  return static_cast<std::size_t>(std::count_if(links.begin(), links.end(), [](const MapLink& l) { return l.revoked; }));
}

ExperienceIndex::ExperienceIndex(const ExperienceMap& map) {
  by_id_.reserve(map.experiences.size());
  for (const MapExperience& e : map.experiences) by_id_.emplace(e.id, &e);
}

const MapExperience* ExperienceIndex::find(int32_t id) const {
  const auto it = by_id_.find(id);
  return it == by_id_.end() ? nullptr : it->second;
}

GroundTruth::GroundTruth(std::vector<PoseSample> samples, std::vector<int64_t> jumps)
    : samples_(std::move(samples)), jumps_(std::move(jumps)) {
  std::sort(jumps_.begin(), jumps_.end());
  std::stable_sort(samples_.begin(), samples_.end(),
                   [](const PoseSample& a, const PoseSample& b) { return a.utime < b.utime; });
  // Keep the last of equal-time samples: the newest publication is the simulator's final word.
  std::vector<PoseSample> unique;
  unique.reserve(samples_.size());
  for (const PoseSample& s : samples_) {
    if (!unique.empty() && unique.back().utime == s.utime) {
      unique.back() = s;
    } else {
      unique.push_back(s);
    }
  }
  samples_ = std::move(unique);
}

namespace {

std::vector<PoseSample> concatenated(const std::vector<PoseSample>& a, const std::vector<PoseSample>& b) {
  std::vector<PoseSample> out = a;
  out.insert(out.end(), b.begin(), b.end());
  return out;
}

int64_t last_utime(const std::vector<PoseSample>& v) {
  int64_t t = std::numeric_limits<int64_t>::min();
  for (const PoseSample& s : v) t = std::max(t, s.utime);
  return t;
}

}  // namespace

GroundTruth::GroundTruth(const std::vector<PoseSample>& samples, const std::vector<PoseSample>& earlier_session,
                         std::vector<int64_t> jumps)
    : GroundTruth(concatenated(samples, earlier_session), std::move(jumps)) {
  // The session that ends first ends before the other begins: no truth in between.
  if (!samples.empty() && !earlier_session.empty()) {
    hole_after_.push_back(std::min(last_utime(samples), last_utime(earlier_session)));
  }
}

bool GroundTruth::breaks_between(int64_t from, int64_t to) const {
  const auto j = std::upper_bound(jumps_.begin(), jumps_.end(), from);
  if (j != jumps_.end() && *j <= to) return true;
  for (const int64_t h : hole_after_) {
    if (from <= h && to > h) return true;
  }
  return false;
}

double GroundTruth::path_length(int64_t from, int64_t to) const {
  if (samples_.empty() || to <= from) return 0.0;
  double d = 0.0;
  std::optional<Pose2> prev = at(from);
  int64_t prev_utime = from;
  const auto step = [&](const Pose2& p, int64_t utime) {
    if (prev && !breaks_between(prev_utime, utime)) d += std::hypot(p.x - prev->x, p.y - prev->y);
    prev = p;
    prev_utime = utime;
  };
  auto it = std::upper_bound(samples_.begin(), samples_.end(), from,
                             [](int64_t t, const PoseSample& s) { return t < s.utime; });
  for (; it != samples_.end() && it->utime < to; ++it) step(it->pose, it->utime);
  if (const std::optional<Pose2> end = at(to)) step(*end, to);
  return d;
}

std::optional<Pose2> GroundTruth::at(int64_t utime) const {
  if (samples_.empty() || utime < samples_.front().utime || utime > samples_.back().utime) {
    return std::nullopt;
  }
  const auto hi = std::lower_bound(samples_.begin(), samples_.end(), utime,
                                   [](const PoseSample& s, int64_t t) { return s.utime < t; });
  if (hi->utime == utime) return hi->pose;
  const auto lo = hi - 1;
  if (std::find(hole_after_.begin(), hole_after_.end(), lo->utime) != hole_after_.end()) return std::nullopt;
  // Never a pose between the place before a kidnap and the place after it.
  if (const auto j = std::upper_bound(jumps_.begin(), jumps_.end(), lo->utime); j != jumps_.end() && *j <= hi->utime) {
    return utime < *j ? lo->pose : hi->pose;
  }
  const double f = static_cast<double>(utime - lo->utime) / static_cast<double>(hi->utime - lo->utime);
  return interpolate(lo->pose, hi->pose, f);
}

// ---- Alignment ----

Alignment align_by_first_experience(const ExperienceMap& map, const GroundTruth& gt) {
  Alignment a;
  const MapExperience* first = nullptr;
  for (const MapExperience& e : map.experiences) {
    if (first == nullptr || e.utime_created < first->utime_created ||
        (e.utime_created == first->utime_created && e.id < first->id)) {
      first = &e;
    }
  }
  if (first == nullptr) {
    a.reason = "the final map has no experiences";
    return a;
  }
  const std::optional<Pose2> g = gt.at(first->utime_created);
  if (!g) {
    a.reason = "no ground truth at the creation time of the first experience (id " +
               std::to_string(first->id) + ")";
    return a;
  }
  // T_world_map ∘ x̂_first = g  ⇒  T_world_map = g ∘ x̂_first⁻¹
  a.T_world_map = compose(*g, inverse(first->pose));
  a.valid = true;
  return a;
}

namespace {

// An estimated pose (map frame) and the ground truth (world) at its time.
using TruthPair = std::pair<Pose2, Pose2>;

// The best-fit rigid SE(2) transform of the pairs' positions (closed form; align_best_fit's).
Alignment align_pairs(std::span<const TruthPair> pairs) {
  Alignment a;
  if (pairs.size() < 2) {
    a.reason = "fewer than 2 pose samples with ground truth";
    return a;
  }
  double px = 0, py = 0, qx = 0, qy = 0;
  for (const auto& [p, q] : pairs) {
    px += p.x;
    py += p.y;
    qx += q.x;
    qy += q.y;
  }
  const double n = static_cast<double>(pairs.size());
  px /= n;
  py /= n;
  qx /= n;
  qy /= n;
  double dot = 0, cross = 0;
  for (const auto& [p, q] : pairs) {
    const double ax = p.x - px, ay = p.y - py, bx = q.x - qx, by = q.y - qy;
    dot += ax * bx + ay * by;
    cross += ax * by - ay * bx;
  }
  if (std::hypot(dot, cross) < 1e-12) {
    a.reason = "pose samples do not span any distance: rotation undetermined";
    return a;
  }
  const double th = std::atan2(cross, dot);
  const double c = std::cos(th), s = std::sin(th);
  a.T_world_map = {qx - (c * px - s * py), qy - (s * px + c * py), wrap_angle(th)};
  a.valid = true;
  return a;
}

}  // namespace

Alignment align_best_fit(const std::vector<PoseSample>& estimate, const GroundTruth& gt) {
  std::vector<TruthPair> pairs;
  for (const PoseSample& s : estimate) {
    if (const auto g = gt.at(s.utime)) pairs.emplace_back(s.pose, *g);
  }
  return align_pairs(pairs);
}

// ---- LEM ----

namespace {

// Events by time, then cycle number (the order slamd produced them in; a log may interleave them).
std::vector<ExperienceEvent> in_time_order(std::vector<ExperienceEvent> events) {
  std::stable_sort(events.begin(), events.end(), [](const ExperienceEvent& a, const ExperienceEvent& b) {
    return a.utime != b.utime ? a.utime < b.utime : a.cycle < b.cycle;
  });
  return events;
}

// Creation time of every experience: utime_created in the final map, else its NEW_EXPERIENCE event.
std::map<int32_t, int64_t> creation_times(const std::vector<ExperienceEvent>& sorted_events, const ExperienceMap& map) {
  std::map<int32_t, int64_t> created;
  for (const MapExperience& e : map.experiences) created[e.id] = e.utime_created;
  for (const ExperienceEvent& e : sorted_events) {
    if (e.type == EventType::kNewExperience && e.to_id != e.from_id) created.emplace(e.to_id, e.utime);
  }
  return created;
}

// The median of a non-empty list (the mean of the middle two for an even count).
double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  const std::size_t n = v.size();
  return n % 2 == 1 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

class StatsAccumulator {
 public:
  void add(double abs_error) {
    n_ += 1;
    sum_ += abs_error;
    sum_sq_ += abs_error * abs_error;
  }
  ErrorStats stats() const {
    ErrorStats s;
    if (n_ == 0) return s;
    const double n = static_cast<double>(n_);
    s.rmse = std::sqrt(sum_sq_ / n);
    s.mean_abs = sum_ / n;
    s.std_abs = std::sqrt(std::max(0.0, sum_sq_ / n - s.mean_abs * s.mean_abs));
    return s;
  }

 private:
  std::size_t n_ = 0;
  double sum_ = 0.0;
  double sum_sq_ = 0.0;
};

}  // namespace

LemResult compute_lem(const std::vector<PoseSample>& estimate, const GroundTruth& gt,
                      const Pose2& T_world_map) {
  LemResult r;
  StatsAccumulator pos;
  StatsAccumulator ori;
  for (const PoseSample& s : estimate) {
    const std::optional<Pose2> g = gt.at(s.utime);
    if (!g) {
      ++r.samples_outside_gt;
      continue;
    }
    const Pose2 w = compose(T_world_map, s.pose);
    pos.add(std::hypot(w.x - g->x, w.y - g->y));
    ori.add(std::abs(angle_diff(w.theta, g->theta)));
    ++r.samples_used;
  }
  r.position_m = pos.stats();
  r.orientation_rad = ori.stats();
  return r;
}

// ---- ATE ----

namespace {

// Position errors of the pairs' estimates under `T_world_map`.
std::vector<double> position_errors(std::span<const TruthPair> pairs, const Pose2& T_world_map) {
  std::vector<double> e;
  e.reserve(pairs.size());
  for (const auto& [est, truth] : pairs) {
    const Pose2 w = compose(T_world_map, est);
    e.push_back(std::hypot(w.x - truth.x, w.y - truth.y));
  }
  return e;
}

double rms(const std::vector<double>& e, std::size_t begin, std::size_t end) {
  double sq = 0.0;
  for (std::size_t i = begin; i < end; ++i) sq += e[i] * e[i];
  return std::sqrt(sq / static_cast<double>(end - begin));
}

}  // namespace

std::vector<PoseSample> claimed_poses(const std::vector<PoseSample>& estimate, const std::vector<StateSample>& states) {
  if (states.empty() || estimate.empty()) return estimate;
  if (states.size() != estimate.size()) {
    throw std::invalid_argument(std::to_string(states.size()) + " localisation states for " +
                                std::to_string(estimate.size()) + " pose samples");
  }
  std::vector<PoseSample> claimed;
  claimed.reserve(estimate.size());
  for (std::size_t i = 0; i < estimate.size(); ++i) {
    if (!states[i].localising) claimed.push_back(estimate[i]);
  }
  return claimed;
}

AteResult compute_ate(const std::vector<PoseSample>& estimate, const std::vector<StateSample>& states,
                      const GroundTruth& gt, double window_laps) {
  AteResult r;
  r.window_laps = window_laps;
  const std::vector<PoseSample> claimed = claimed_poses(estimate, states);
  r.samples_localising = estimate.size() - claimed.size();
  // Each claimed pose with the truth at its time, looked up once.
  std::vector<PoseSample> used;
  std::vector<TruthPair> pairs;
  for (const PoseSample& s : claimed) {
    if (const std::optional<Pose2> g = gt.at(s.utime)) {
      used.push_back(s);
      pairs.emplace_back(s.pose, *g);
    }
  }
  r.samples_outside_gt = claimed.size() - used.size();
  r.samples_used = used.size();
  r.alignment = align_pairs(pairs);
  if (!r.alignment.valid) return r;
  const std::vector<double> e = position_errors(pairs, r.alignment.T_world_map);
  AteStats st;
  st.rmse = rms(e, 0, e.size());
  for (const double x : e) {
    st.mean += x;
    st.max = std::max(st.max, x);
  }
  st.mean /= static_cast<double>(e.size());
  st.median = median(e);
  r.position_m = st;

  r.lap_length_m = lap_length(gt);
  if (!r.lap_length_m || !(window_laps > 0.0)) return r;
  // Travel (ground truth, never across a jump) from the first sample used, sample by sample.
  const double window_m = window_laps * *r.lap_length_m;
  std::size_t begin = 0;
  double begin_m = 0.0;
  double travelled = 0.0;
  const auto close_window = [&](std::size_t end, double to_m) {
    AteWindow w;
    w.from_lap = begin_m / *r.lap_length_m;
    w.to_lap = to_m / *r.lap_length_m;
    w.begin_utime = used[begin].utime;
    w.end_utime = used[end - 1].utime;
    w.samples = end - begin;
    w.rmse = rms(e, begin, end);
    const std::span<const TruthPair> part(pairs.data() + begin, end - begin);
    if (const Alignment own = align_pairs(part); own.valid) {
      w.rmse_own_fit = rms(position_errors(part, own.T_world_map), 0, part.size());
    }
    r.windows.push_back(w);
    begin = end;
  };
  // A window ends where the travel reaches the next multiple of the window's length.
  double last_m = 0.0;
  for (std::size_t i = 1; i < used.size(); ++i) {
    travelled += gt.path_length(used[i - 1].utime, used[i].utime);
    if (std::floor(travelled / window_m) > std::floor(begin_m / window_m)) {
      close_window(i, last_m);
      begin_m = travelled;
    }
    last_m = travelled;
  }
  close_window(used.size(), travelled);
  return r;
}

// ---- ExM ----

std::optional<int64_t> base_set_end(const GroundTruth& gt, const EvalParams& params) {
  if (gt.empty()) return std::nullopt;
  if (params.base_duration_s) {
    return gt.begin_utime() + seconds_to_utime(*params.base_duration_s);
  }
  // Net polar-angle travel around the centre (so back-and-forth does not add up). Samples within
  // 1 cm of the centre are skipped: their polar angle is meaningless.
  std::optional<double> prev_phi;
  int64_t prev_utime = 0;
  double travelled = 0.0;
  for (const PoseSample& s : gt.samples()) {
    const double dx = s.pose.x - params.centre_x;
    const double dy = s.pose.y - params.centre_y;
    if (std::hypot(dx, dy) < 0.01) continue;
    const double phi = std::atan2(dy, dx);
    if (prev_phi && gt.breaks_between(prev_utime, s.utime)) prev_phi.reset();  // a kidnap is no travel
    if (prev_phi) {
      const double next = travelled + angle_diff(phi, *prev_phi);
      if (std::abs(next) >= kTwoPi) {
        // Interpolate the crossing within this sample interval.
        const double f = (kTwoPi - std::abs(travelled)) / (std::abs(next) - std::abs(travelled));
        return prev_utime + static_cast<int64_t>(std::llround(f * static_cast<double>(s.utime - prev_utime)));
      }
      travelled = next;
    }
    prev_phi = phi;
    prev_utime = s.utime;
  }
  return std::nullopt;
}

const char* closure_name(Closure c) {
  switch (c) {
    case Closure::kCorrect: return "correct";
    case Closure::kNeighbourMiss: return "neighbour";
    case Closure::kFalse: return "false";
  }
  return "false";
}

Closure classify_closure(double position_error_m, double angle_error_rad, const EvalParams& params) {
  if (position_error_m <= params.correct_position_m && angle_error_rad <= params.correct_angle_rad) {
    return Closure::kCorrect;
  }
  if (position_error_m > params.false_closure_position_m || angle_error_rad > params.false_closure_angle_rad) {
    return Closure::kFalse;
  }
  return Closure::kNeighbourMiss;
}

namespace {

// An event that puts the robot at experience e.to_id, judged by the truth now and where the target
// was created (alignment-free).
Relocalisation judge_claim(const ExperienceEvent& e, const Pose2& gt_now, const Pose2& gt_target, const EvalParams& params) {
  Relocalisation rl;
  rl.utime = e.utime;
  rl.from_id = e.from_id;
  rl.to_id = e.to_id;
  rl.gt_now = gt_now;
  rl.gt_target_created = gt_target;
  rl.position_error_m = std::hypot(gt_now.x - gt_target.x, gt_now.y - gt_target.y);
  rl.angle_error_rad = std::abs(angle_diff(gt_now.theta, gt_target.theta));
  rl.closure = classify_closure(rl.position_error_m, rl.angle_error_rad, params);
  rl.correct = rl.closure == Closure::kCorrect;
  return rl;
}

// ExM over `events`, the base set ending at `end` (none: everything is base); `origin` is the time
// base_end_s counts from. With ground truth every re-localisation is judged; without (`gt` empty),
// the events are only counted and nothing that judges is set.
ExmResult exm(const std::vector<ExperienceEvent>& events_in, const ExperienceMap& map, const GroundTruth& gt,
              const EvalParams& params, std::optional<int64_t> end, int64_t origin) {
  ExmResult r;
  const bool judge = !gt.empty();
  const std::vector<ExperienceEvent> events = in_time_order(events_in);

  const std::map<int32_t, int64_t> created = creation_times(events, map);

  r.base_end_found = end.has_value();
  r.base_end_utime = end.value_or(std::numeric_limits<int64_t>::max());
  if (end) r.base_end_s = utime_delta_seconds(origin, *end);
  for (const auto& [id, t] : created) {
    if (t <= r.base_end_utime) ++r.base_set_size;
  }

  bool valid_state = true;  // experiences are valid until an incorrect re-localisation
  std::vector<double> steps_m, steps_rad;  // experience spacing
  for (const ExperienceEvent& e : events) {
    if (e.type == EventType::kSameExperience) continue;
    if (e.to_id == e.from_id) {
      if (e.type == EventType::kRelocalise) ++r.relocalise_to_current;
      continue;
    }
    const std::optional<Pose2> gt_now = judge ? gt.at(e.utime) : Pose2{};
    if (!gt_now) {
      ++r.events_outside_gt;
      continue;
    }
    const bool after = e.utime > r.base_end_utime;
    if (e.type == EventType::kNewExperience) {
      ++r.experiences_created;
      if (judge && valid_state) ++r.valid_experiences;
      if (after) ++r.experience_events_after_base;
      const auto prev = created.find(e.from_id);
      if (judge && prev != created.end()) {
        const std::optional<Pose2> a = gt.at(prev->second);
        const std::optional<Pose2> b = gt.at(created.at(e.to_id));
        if (a && b) {
          steps_m.push_back(std::hypot(b->x - a->x, b->y - a->y));
          steps_rad.push_back(std::abs(angle_diff(b->theta, a->theta)));
        }
      }
      continue;
    }
    const auto target = created.find(e.to_id);
    if (target == created.end() || target->second > e.utime) {
      ++r.relocalise_unknown_target;
      continue;
    }
    if (!judge) {
      ++r.relocalisations_total;
      if (after) {
        ++r.experience_events_after_base;
        ++r.relocalisations_after_base;
      }
      continue;
    }
    const std::optional<Pose2> gt_target = gt.at(target->second);
    if (!gt_target) {
      ++r.events_outside_gt;
      continue;
    }
    Relocalisation rl = judge_claim(e, *gt_now, *gt_target, params);
    rl.after_base_set = after;
    ++r.relocalisations_total;
    if (rl.correct) ++r.correct_total;
    if (rl.closure == Closure::kNeighbourMiss) ++r.neighbour_misses;
    if (rl.closure == Closure::kFalse) {
      ++r.false_closures;
      r.false_closure_worst_m = std::max(r.false_closure_worst_m.value_or(0.0), rl.position_error_m);
    }
    if (after) {
      ++r.experience_events_after_base;
      ++r.relocalisations_after_base;
      if (rl.correct) ++r.correct_after_base;
    }
    valid_state = rl.correct;
    r.relocalisations.push_back(rl);
  }

  if (r.experience_events_after_base > 0) {
    r.arr = static_cast<double>(r.relocalisations_after_base) /
            static_cast<double>(r.experience_events_after_base);
  }
  if (!judge) return r;
  if (r.relocalisations_total > 0) {
    r.arcr = static_cast<double>(r.correct_total) / static_cast<double>(r.relocalisations_total);
  }
  if (r.relocalisations_after_base > 0) {
    r.arcr_after_base =
        static_cast<double>(r.correct_after_base) / static_cast<double>(r.relocalisations_after_base);
  }
  if (r.false_closures + r.neighbour_misses > 0) {
    r.neighbour_miss_share =
        static_cast<double>(r.neighbour_misses) / static_cast<double>(r.false_closures + r.neighbour_misses);
  }
  r.spacing_steps = steps_m.size();
  if (!steps_m.empty()) {
    r.spacing_median_m = median(steps_m);
    r.spacing_median_heading_rad = median(steps_rad);
  }
  if (r.experiences_created > 0) {
    r.valid_fraction = static_cast<double>(r.valid_experiences) / static_cast<double>(r.experiences_created);
  }
  return r;
}

}  // namespace

ExmResult compute_exm(const std::vector<ExperienceEvent>& events, const ExperienceMap& map, const GroundTruth& gt,
                      const EvalParams& params) {
  return exm(events, map, gt, params, base_set_end(gt, params), gt.begin_utime());
}

// ---- EnM ----

EnmResult compute_enm(const ExperienceMap& map, const GroundTruth& gt) {
  EnmResult r;
  double sum_t = 0.0;
  double sum_r = 0.0;
  const ExperienceIndex by_id(map);
  for (const MapLink& l : map.links) {
    const MapExperience* i = by_id.find(l.from_id);
    const MapExperience* j = by_id.find(l.to_id);
    if (i == nullptr || j == nullptr) {
      ++r.links_excluded;
      continue;
    }
    const std::optional<Pose2> gi = gt.at(i->utime_created);
    const std::optional<Pose2> gj = gt.at(j->utime_created);
    if (!gi || !gj) {
      ++r.links_excluded;
      continue;
    }
    const Pose2 d_hat = between(i->pose, j->pose);
    const Pose2 d_true = between(*gi, *gj);
    const Pose2 e = between(d_hat, d_true);
    sum_t += e.x * e.x + e.y * e.y;
    sum_r += e.theta * e.theta;
    ++r.links_used;
  }
  if (r.links_used > 0) {
    const double n = static_cast<double>(r.links_used);
    r.translation = sum_t / n;
    r.rotation = sum_r / n;
    r.enm = (sum_t + sum_r) / n;
  }
  return r;
}

// ---- Localisation ----

const char* instant_name(LocalisationInstant::Kind kind) {
  return kind == LocalisationInstant::Kind::kKidnap ? "kidnap" : "session_start";
}

std::optional<double> lap_length(const GroundTruth& gt) {
  double distance = 0.0;
  double turned = 0.0;
  const std::vector<PoseSample>& v = gt.samples();
  for (std::size_t i = 1; i < v.size(); ++i) {
    if (gt.breaks_between(v[i - 1].utime, v[i].utime)) continue;
    distance += std::hypot(v[i].pose.x - v[i - 1].pose.x, v[i].pose.y - v[i - 1].pose.y);
    turned += std::abs(angle_diff(v[i].pose.theta, v[i - 1].pose.theta));
  }
  if (turned < kPi) return std::nullopt;
  return kTwoPi * distance / turned;
}

namespace {

// Seconds the state was LOCALISING in [from, to): each sample holds until the next one (the last
// until `to`).
double localising_seconds(const std::vector<StateSample>& sorted, int64_t from, int64_t to) {
  int64_t total = 0;
  for (std::size_t i = 0; i < sorted.size(); ++i) {
    if (!sorted[i].localising) continue;
    const int64_t a = std::max(sorted[i].utime, from);
    const int64_t b = std::min(i + 1 < sorted.size() ? sorted[i + 1].utime : to, to);
    if (b > a) total += b - a;
  }
  return static_cast<double>(total) * 1e-6;
}

// One event of a window judged as a claim of where the robot is.
struct Claim {
  ExperienceEvent event;
  Relocalisation judged;
  bool known_before = false;  // its target was created at or before the instant
};

}  // namespace

LocalisationReport compute_localisation(const std::vector<ExperienceEvent>& events_in, const ExperienceMap& map,
                                        const GroundTruth& truth, const GroundTruth& own,
                                        std::vector<LocalisationInstant> instants,
                                        const std::vector<StateSample>& states_in, const EvalParams& params) {
  LocalisationReport report;
  const std::vector<ExperienceEvent> events = in_time_order(events_in);
  const std::map<int32_t, int64_t> created = creation_times(events, map);
  std::vector<StateSample> states = states_in;
  if (states.empty()) {
    for (const ExperienceEvent& e : events) states.push_back({e.utime, e.localising});
  }
  std::stable_sort(states.begin(), states.end(), [](const StateSample& a, const StateSample& b) { return a.utime < b.utime; });
  std::stable_sort(instants.begin(), instants.end(),
                   [](const LocalisationInstant& a, const LocalisationInstant& b) { return a.utime < b.utime; });
  int64_t log_end = own.empty() ? std::numeric_limits<int64_t>::min() : own.end_utime();
  if (!events.empty()) log_end = std::max(log_end, events.back().utime);
  if (!states.empty()) log_end = std::max(log_end, states.back().utime);
  report.lap_length_m = lap_length(own);

  StatsAccumulator lem_all;
  for (std::size_t k = 0; k < instants.size(); ++k) {
    Localisation loc;
    loc.instant = instants[k];
    const int64_t t0 = loc.instant.utime;
    loc.window_end_utime = k + 1 < instants.size() ? instants[k + 1].utime : std::max(log_end, t0);
    loc.gt_at = own.at(t0);
    // The experience current at the instant: staying on it is not a claim.
    int32_t stale = -1;
    const auto first_after = std::upper_bound(events.begin(), events.end(), t0,
                                              [](int64_t t, const ExperienceEvent& e) { return t < e.utime; });
    if (first_after != events.begin()) {
      stale = std::prev(first_after)->to_id;
    } else if (first_after != events.end()) {
      stale = first_after->from_id;
    }
    std::vector<Claim> claims;
    const bool last = k + 1 == instants.size();  // its window includes the log's last event
    for (auto it = first_after; it != events.end() && (it->utime < loc.window_end_utime ||
                                                       (last && it->utime == loc.window_end_utime));
         ++it) {
      const ExperienceEvent& e = *it;
      // A claim moves the robot onto a place the map holds. Staying there (SAME_EXPERIENCE) is no new
      // claim: the pose is then that place plus the odometry since, and the place's own truth falls
      // behind at the robot's speed (0.25 m in 2-3 cycles), which is not an error of the pose.
      if (e.type != EventType::kRelocalise || e.localising) continue;
      if (e.to_id == stale && e.to_id == e.from_id) continue;
      const auto target = created.find(e.to_id);
      const std::optional<Pose2> now = truth.at(e.utime);
      const std::optional<Pose2> then =
          target != created.end() && target->second <= e.utime ? truth.at(target->second) : std::nullopt;
      if (!now || !then) {
        ++loc.unjudged_events;
        continue;
      }
      claims.push_back({e, judge_claim(e, *now, *then, params), target->second <= t0});
    }
    loc.judged_events = claims.size();
    std::size_t after_last_false = 0;
    for (std::size_t i = 0; i < claims.size(); ++i) {
      if (claims[i].judged.closure == Closure::kFalse) after_last_false = i + 1;
    }
    std::size_t localised_at = claims.size();
    for (std::size_t i = after_last_false; i < claims.size(); ++i) {
      if (claims[i].judged.correct && claims[i].known_before) {
        localised_at = i;
        break;
      }
    }
    int32_t last_false_target = -1;
    for (std::size_t i = 0; i < localised_at; ++i) {
      const Relocalisation& r = claims[i].judged;
      if (r.closure != Closure::kFalse) {
        last_false_target = -1;
        continue;
      }
      if (r.to_id != last_false_target) {
        ++loc.false_localisations;
        loc.false_events.push_back(r);
      }
      last_false_target = r.to_id;
    }
    loc.localising_s = localising_seconds(states, t0, loc.window_end_utime);
    if (localised_at < claims.size()) {
      const Claim& c = claims[localised_at];
      loc.localised = true;
      loc.localised_utime = c.event.utime;
      loc.localised_by = c.event;
      loc.gt_localised = c.judged.gt_now;
      loc.gt_target_created = c.judged.gt_target_created;
      loc.position_error_m = c.judged.position_error_m;
      loc.angle_error_rad = c.judged.angle_error_rad;
      loc.time_s = utime_delta_seconds(t0, c.event.utime);
      loc.distance_m = own.path_length(t0, c.event.utime);
      if (report.lap_length_m) loc.laps = *loc.distance_m / *report.lap_length_m;
      StatsAccumulator pos;
      StatsAccumulator ori;
      for (std::size_t i = localised_at; i < claims.size(); ++i) {
        pos.add(claims[i].judged.position_error_m);
        ori.add(claims[i].judged.angle_error_rad);
        lem_all.add(claims[i].judged.position_error_m);
      }
      loc.lem_events = claims.size() - localised_at;
      loc.lem_after_m = pos.stats().mean_abs;
      loc.lem_after_angle_rad = ori.stats().mean_abs;
      report.lem_events += loc.lem_events;
    }
    report.instants.push_back(std::move(loc));
  }
  bool all_laps = !report.instants.empty();
  for (const Localisation& l : report.instants) {
    report.localised += l.localised;
    report.within_one_lap += l.laps && *l.laps <= 1.0;
    report.within_two_laps += l.laps && *l.laps <= 2.0;
    if (l.laps) {
      report.worst_laps = std::max(report.worst_laps.value_or(0.0), *l.laps);
    } else {
      all_laps = false;
    }
    report.false_localisations += l.false_localisations;
    report.false_localisations_max = std::max(report.false_localisations_max, l.false_localisations);
    report.with_false_localisation += l.false_localisations > 0;
    report.localising_s += l.localising_s;
  }
  if (!all_laps) report.worst_laps.reset();
  if (report.lem_events > 0) report.lem_after_m = lem_all.stats().mean_abs;
  return report;
}

// ---- Everything ----

namespace {

std::vector<int64_t> kidnap_utimes(const EvalInput& input) {
  std::vector<int64_t> out;
  for (const PoseSample& k : input.kidnaps) out.push_back(k.utime);
  return out;
}

}  // namespace

GroundTruth truth_of(const EvalInput& input) {
  if (input.map_ground_truth.empty()) return GroundTruth(input.ground_truth, kidnap_utimes(input));
  return GroundTruth(input.ground_truth, input.map_ground_truth, kidnap_utimes(input));
}

std::vector<LocalisationInstant> localisation_instants(const EvalInput& input, const EvalParams& params) {
  std::vector<LocalisationInstant> out;
  if (input.ground_truth.empty()) return out;
  const int64_t start = GroundTruth(input.ground_truth).begin_utime();
  bool session = params.session_start;
  for (const MapExperience& e : input.map.experiences) session = session || e.utime_created < start;
  if (session) out.push_back({LocalisationInstant::Kind::kSessionStart, start});
  for (const PoseSample& k : input.kidnaps) out.push_back({LocalisationInstant::Kind::kKidnap, k.utime});
  std::stable_sort(out.begin(), out.end(),
                   [](const LocalisationInstant& a, const LocalisationInstant& b) { return a.utime < b.utime; });
  return out;
}

int64_t run_start_utime(const EvalInput& input) {
  if (!input.ground_truth.empty()) return GroundTruth(input.ground_truth).begin_utime();
  std::optional<int64_t> first;
  for (const PoseSample& s : input.estimate) first = std::min(first.value_or(s.utime), s.utime);
  for (const ExperienceEvent& e : input.events) first = std::min(first.value_or(e.utime), e.utime);
  return first.value_or(0);
}

ExmResult count_exm_without_truth(const std::vector<ExperienceEvent>& events, const ExperienceMap& map,
                                  const EvalParams& params, int64_t start_utime) {
  std::optional<int64_t> end;
  if (params.base_duration_s) end = start_utime + seconds_to_utime(*params.base_duration_s);
  return exm(events, map, GroundTruth({}), params, end, start_utime);
}

LinkJudgement judge_links(const ExperienceMap& map, const GroundTruth& gt, const EvalParams& params) {
  LinkJudgement j;
  const ExperienceIndex index(map);
  for (const MapLink& l : map.links) {
    const MapExperience* a = index.find(l.from_id);
    const MapExperience* b = index.find(l.to_id);
    if (a == nullptr || b == nullptr) continue;
    const std::optional<Pose2> ta = gt.at(a->utime_created), tb = gt.at(b->utime_created);
    if (!ta || !tb) continue;
    ++j.judged;
    const Pose2 claimed = compose(*ta, l.delta);
    const double position_m = std::hypot(claimed.x - tb->x, claimed.y - tb->y);
    const double angle_rad = std::abs(angle_diff(claimed.theta, tb->theta));
    const bool wrong = position_m > params.false_closure_position_m || angle_rad > params.false_closure_angle_rad;
    if (wrong) ++j.wrong;
    if (wrong && !l.revoked) ++j.wrong_kept;
    if (!wrong && l.revoked) ++j.right_revoked;
    if (!l.revoked) j.worst_kept_m = std::max(j.worst_kept_m.value_or(0.0), position_m);
  }
  return j;
}

EvalResult evaluate(const EvalInput& input, const EvalParams& params) {
  EvalResult r;
  if (input.ground_truth.empty()) {
    r.ground_truth = false;
    r.alignment.reason = r.ate.alignment.reason = "no ground truth";
    r.exm = count_exm_without_truth(input.events, input.map, params, run_start_utime(input));
    return r;
  }
  // This log's truth decides the base set and the distances; the map's session's too judges.
  const GroundTruth own(input.ground_truth, kidnap_utimes(input));
  const GroundTruth gt = truth_of(input);
  r.alignment = align_by_first_experience(input.map, gt);
  if (r.alignment.valid) r.lem = compute_lem(input.estimate, gt, r.alignment.T_world_map);
  r.ate = compute_ate(input.estimate, input.states, gt, params.ate_window_laps);
  r.exm = exm(input.events, input.map, gt, params, base_set_end(own, params), own.begin_utime());
  r.enm = compute_enm(input.map, gt);
  r.links = judge_links(input.map, gt, params);
  const std::vector<LocalisationInstant> instants = localisation_instants(input, params);
  if (!instants.empty()) {
    r.localisation = compute_localisation(input.events, input.map, gt, own, instants, input.states, params);
  }
  return r;
}

// ---- Per-cycle trace ----

std::vector<CycleTrace> trace_cycles(const EvalInput& input, const ExmResult& exm,
                                     const LocalisationReport* localisation) {
  const GroundTruth gt = truth_of(input);
  const int64_t start = run_start_utime(input);
  const std::vector<ExperienceEvent> events = in_time_order(input.events);
  std::map<std::pair<int64_t, int32_t>, const Relocalisation*> relocs;
  for (const Relocalisation& r : exm.relocalisations) relocs[{r.utime, r.to_id}] = &r;
  std::map<int64_t, const TemplateMatch*> matches;
  for (const TemplateMatch& m : input.matches) matches[m.cycle] = &m;
  // The localisation metric's marks, by (utime, to_id) of the event they mark; an instant marks the
  // first event after it.
  std::map<std::pair<int64_t, int32_t>, std::vector<std::string>> marks;
  if (localisation != nullptr) {
    for (const Localisation& l : localisation->instants) {
      const auto first = std::upper_bound(events.begin(), events.end(), l.instant.utime,
                                          [](int64_t t, const ExperienceEvent& e) { return t < e.utime; });
      if (first != events.end()) marks[{first->utime, first->to_id}].push_back(instant_name(l.instant.kind));
      for (const Relocalisation& f : l.false_events) marks[{f.utime, f.to_id}].push_back("false_localisation");
      if (l.localised) marks[{l.localised_by.utime, l.localised_by.to_id}].push_back("localised");
    }
  }

  std::vector<CycleTrace> out;
  out.reserve(events.size());
  std::vector<FaultEvent> faults = input.faults;
  std::stable_sort(faults.begin(), faults.end(), [](const FaultEvent& a, const FaultEvent& b) { return a.utime < b.utime; });
  std::map<std::string, int> active;  // fault name -> how many times it is active now
  std::size_t next_fault = 0;
  for (const ExperienceEvent& e : events) {
    for (; next_fault < faults.size() && faults[next_fault].utime <= e.utime; ++next_fault) {
      int& n = active[faults[next_fault].name];
      n = std::max(0, n + (faults[next_fault].active ? 1 : -1));
    }
    CycleTrace row;
    for (const auto& [name, n] : active) {
      if (n > 0) row.active_faults.push_back(name);
    }
    row.event = e;
    row.t_s = utime_delta_seconds(start, e.utime);
    row.gt = gt.at(e.utime);
    if (e.type == EventType::kRelocalise) {
      const auto r = relocs.find({e.utime, e.to_id});
      if (r != relocs.end()) row.relocalisation = *r->second;
    }
    const auto m = matches.find(e.cycle);
    if (m != matches.end()) row.match = *m->second;
    if (const auto k = marks.find({e.utime, e.to_id}); k != marks.end()) {
      row.localisation_marks = std::move(k->second);
      marks.erase(k);  // on one event only
    }
    out.push_back(std::move(row));
  }
  return out;
}

}  // namespace whiskeye::eval
