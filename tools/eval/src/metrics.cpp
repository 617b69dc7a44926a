// LEM, ExM and EnM as specified in ../shared/design/metrics.md (see metrics.h for the contract).
#include "whiskeye/eval/metrics.h"

#include "whiskeye/common/utime.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <utility>

namespace whiskeye::eval {

const MapExperience* ExperienceMap::find(int32_t id) const {
  for (const MapExperience& e : experiences) {
    if (e.id == id) return &e;
  }
  return nullptr;
}

ExperienceIndex::ExperienceIndex(const ExperienceMap& map) {
  by_id_.reserve(map.experiences.size());
  for (const MapExperience& e : map.experiences) by_id_.emplace(e.id, &e);
}

const MapExperience* ExperienceIndex::find(int32_t id) const {
  const auto it = by_id_.find(id);
  return it == by_id_.end() ? nullptr : it->second;
}

GroundTruth::GroundTruth(std::vector<PoseSample> samples) : samples_(std::move(samples)) {
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

std::optional<Pose2> GroundTruth::at(int64_t utime) const {
  if (samples_.empty() || utime < samples_.front().utime || utime > samples_.back().utime) {
    return std::nullopt;
  }
  const auto hi = std::lower_bound(samples_.begin(), samples_.end(), utime,
                                   [](const PoseSample& s, int64_t t) { return s.utime < t; });
  if (hi->utime == utime) return hi->pose;
  const auto lo = hi - 1;
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

Alignment align_best_fit(const std::vector<PoseSample>& estimate, const GroundTruth& gt) {
  Alignment a;
  std::vector<std::pair<Pose2, Pose2>> pairs;  // (estimate in map, ground truth in world)
  for (const PoseSample& s : estimate) {
    if (const auto g = gt.at(s.utime)) pairs.emplace_back(s.pose, *g);
  }
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

// ---- LEM ----

namespace {

// Events by time, then cycle number (the order slamd produced them in; a log may interleave them).
std::vector<ExperienceEvent> in_time_order(std::vector<ExperienceEvent> events) {
  std::stable_sort(events.begin(), events.end(), [](const ExperienceEvent& a, const ExperienceEvent& b) {
    return a.utime != b.utime ? a.utime < b.utime : a.cycle < b.cycle;
  });
  return events;
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

// The median of a non-empty list (the mean of the middle two for an even count).
double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  const std::size_t n = v.size();
  return n % 2 == 1 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

// ExM over `events`, the base set ending at `end` (none: everything is base); `origin` is the time
// base_end_s counts from. With ground truth every re-localisation is judged; without (`gt` empty),
// the events are only counted and nothing that judges is set.
ExmResult exm(const std::vector<ExperienceEvent>& events_in, const ExperienceMap& map, const GroundTruth& gt,
              const EvalParams& params, std::optional<int64_t> end, int64_t origin) {
  ExmResult r;
  const bool judge = !gt.empty();
  const std::vector<ExperienceEvent> events = in_time_order(events_in);

  std::map<int32_t, int64_t> created;
  for (const MapExperience& e : map.experiences) created[e.id] = e.utime_created;
  for (const ExperienceEvent& e : events) {
    if (e.type == EventType::kNewExperience && e.to_id != e.from_id) created.emplace(e.to_id, e.utime);
  }

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
    Relocalisation rl;
    rl.utime = e.utime;
    rl.from_id = e.from_id;
    rl.to_id = e.to_id;
    rl.gt_now = *gt_now;
    rl.gt_target_created = *gt_target;
    rl.position_error_m = std::hypot(gt_now->x - gt_target->x, gt_now->y - gt_target->y);
    rl.angle_error_rad = std::abs(angle_diff(gt_now->theta, gt_target->theta));
    rl.closure = classify_closure(rl.position_error_m, rl.angle_error_rad, params);
    rl.correct = rl.closure == Closure::kCorrect;
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

// ---- Everything ----

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

EvalResult evaluate(const EvalInput& input, const EvalParams& params) {
  EvalResult r;
  if (input.ground_truth.empty()) {
    r.ground_truth = false;
    r.alignment.reason = r.best_fit.reason = "no ground truth";
    r.exm = count_exm_without_truth(input.events, input.map, params, run_start_utime(input));
    return r;
  }
  const GroundTruth gt(input.ground_truth);
  r.alignment = align_by_first_experience(input.map, gt);
  r.best_fit = align_best_fit(input.estimate, gt);
  if (r.alignment.valid) r.lem = compute_lem(input.estimate, gt, r.alignment.T_world_map);
  if (r.best_fit.valid) r.lem_best_fit = compute_lem(input.estimate, gt, r.best_fit.T_world_map);
  r.exm = compute_exm(input.events, input.map, gt, params);
  r.enm = compute_enm(input.map, gt);
  return r;
}

// ---- Per-cycle trace ----

std::vector<CycleTrace> trace_cycles(const EvalInput& input, const ExmResult& exm) {
  const GroundTruth gt(input.ground_truth);
  const int64_t start = run_start_utime(input);
  const std::vector<ExperienceEvent> events = in_time_order(input.events);
  std::map<std::pair<int64_t, int32_t>, const Relocalisation*> relocs;
  for (const Relocalisation& r : exm.relocalisations) relocs[{r.utime, r.to_id}] = &r;
  std::map<int64_t, const TemplateMatch*> matches;
  for (const TemplateMatch& m : input.matches) matches[m.cycle] = &m;

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
    out.push_back(std::move(row));
  }
  return out;
}

}  // namespace whiskeye::eval
