// Global localisation: hypotheses weighed over cycles, kidnap detection. See localiser.h.
#include "whiskeye/slam/localiser.h"

#include "binary_io.h"
#include "counters.h"
#include "whiskeye/slam/experience_map.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <unordered_map>
#include <stdexcept>
#include <string>

namespace whiskeye::slam {

void load(const ParamNode& n, LocaliserParams& p) {
  n.get("kidnap_disagreements", p.kidnap_disagreements, 0, 1000);
  n.get("kidnap_window", p.kidnap_window, 1, 1000);
  if (p.kidnap_disagreements > p.kidnap_window) {
    n.fail("kidnap_disagreements", "is " + std::to_string(p.kidnap_disagreements) + ", more than kidnap_window (" +
                                       std::to_string(p.kidnap_window) + "): a kidnap could never be detected");
  }
  n.get("radius", p.radius, 0.0, 100.0);
  n.get("heading", p.heading, 0.0, kPi);
  n.get("commit_score", p.commit_score, 1, 1000);
  n.get("commit_margin", p.commit_margin, 0, 1000);
  n.get("max_hypotheses", p.max_hypotheses, 1, 100000);
  n.get("drop_score", p.drop_score, -1000, 0);
  n.get("give_up_m", p.give_up_m, 0.0, 1e6);
  n.get("resume_gap_s", p.resume_gap_s, 0.0, 1e9);
}

Localiser::Localiser(const LocaliserParams& params) : params_(params) {}

void Localiser::start(bool with_prior, int prior_score, int evidence_below) {
  state_ = LocalisationState::Localising;
  hyps_.clear();
  recent_.clear();
  evidence_below_ = evidence_below;
  localising_m_ = 0.0;
  if (with_prior) hyps_.push_back({Pose2{}, -1, prior_score, true});
}

bool Localiser::has_prior() const {
  return std::any_of(hyps_.begin(), hyps_.end(), [](const Hypothesis& h) { return h.prior; });
}

bool Localiser::on_tracking_recognition(bool refused, int recognised_template, int first_new_id,
                                        const ExperienceMap& map) {
  if (localising() || recognised_template < 0) return false;
  // The experiences made since the oldest disagreement still in the window are no evidence.
  const auto first_refused = std::find_if(recent_.begin(), recent_.end(), [](const TrackedRecognition& r) { return r.refused; });
  const int suspect_from = first_refused != recent_.end() ? first_refused->first_new_id : first_new_id;
  // A disagreement only where the map knows the place the robot thinks it is at (by what it held
  // before the disagreements began): in a place never mapped, a view that is only like one
  // elsewhere is aliasing, not a kidnap, and says nothing either way.
  if (refused && !map.mapped_near(map.current_pose(), std::max(params_.radius, map.drift_budget()), params_.heading,
                                  suspect_from)) {
    return false;
  }
  recent_.push_back({refused, first_new_id});
  while (static_cast<int>(recent_.size()) > params_.kidnap_window) recent_.pop_front();
  const auto refusals = std::count_if(recent_.begin(), recent_.end(), [](const TrackedRecognition& r) { return r.refused; });
  if (params_.kidnap_disagreements <= 0 || refusals < params_.kidnap_disagreements) return false;
  const int evidence_below = std::find_if(recent_.begin(), recent_.end(), [](const TrackedRecognition& r) {
                               return r.refused;
                             })->first_new_id;
  count(kidnaps_detected_);
  // Odometry was trusted until now: where it says the robot is starts as far ahead as a commit must be.
  start(true, params_.commit_margin, evidence_below);
  return true;
}

std::optional<Commit> Localiser::on_localising_cycle(int template_id, double travelled_m, const ExperienceMap& map,
                                                    const std::function<Recognition(int)>& recognises) {
  if (!localising()) return std::nullopt;
  localising_m_ += travelled_m;
  const Pose2 dr = map.current_pose();
  if (template_id >= 0) {
    const std::vector<Experience>& exps = map.experiences();
    const std::vector<int>& candidates = map.experiences_of(template_id);
    std::vector<bool> used(candidates.size(), false);
    std::unordered_map<int, Recognition> recognised;  // by template, this cycle
    const auto recognition = [&](int tid) {
      if (tid == template_id) return Recognition::Recognised;
      if (!recognises || tid < 0) return Recognition::None;
      const auto [it, fresh] = recognised.try_emplace(tid, Recognition::None);
      if (fresh) it->second = recognises(tid);
      return it->second;
    };
    // Around a candidate place: the nearest experience whose template the view is recognised as
    // (-1: none), and whether vision alone would take one there that touch objects to.
    struct Around {
      int recognised = -1;
      bool seen_only = false;
    };
    const auto around = [&](const Pose2& p) {
      Around a;
      double dbest = params_.radius;
      map.for_each_near(p, params_.radius, params_.heading, evidence_below_, [&](int id, double d) {
        const Recognition r = recognition(exps[static_cast<size_t>(id)].template_id);
        if (r == Recognition::Recognised && d <= dbest) {
          a.recognised = id;
          dbest = d;
        }
        a.seen_only = a.seen_only || r == Recognition::SeenOnly;
        return true;
      });
      return a;
    };
    for (Hypothesis& h : hyps_) {
      const Pose2 p = pose_of(h, dr);
      int best = -1;
      double dbest = params_.radius;
      for (size_t k = 0; k < candidates.size(); ++k) {
        if (candidates[k] >= evidence_below_) continue;
        const Experience& e = exps[static_cast<size_t>(candidates[k])];
        const double d = std::hypot(e.pose.x - p.x, e.pose.y - p.y);
        if (d <= dbest && std::abs(angle_diff(e.pose.theta, p.theta)) <= params_.heading) {
          best = static_cast<int>(k);
          dbest = d;
        }
      }
      int anchor = best >= 0 ? candidates[static_cast<size_t>(best)] : -1;
      if (best >= 0) {
        used[static_cast<size_t>(best)] = true;
      } else {
        // Not the best template's place; another template the view is recognised as (a look-alike
        // learnt at another pass) is as good. The map knowing the place and holding nothing the view
        // is recognised as is evidence against, unless vision alone recognises it there and only
        // touch objects (touch varies between passes: it withholds support, it does not contradict);
        // a place never mapped says nothing either way.
        const Around a = around(p);
        anchor = a.recognised;
        if (anchor < 0) {
          if (!a.seen_only && map.mapped_near(p, params_.radius, params_.heading, evidence_below_)) --h.score;
          continue;
        }
      }
      ++h.score;
      // Re-anchored: from here the hypothesis is that experience (its drift so far removed).
      h.anchor = anchor;
      h.correction = compose(exps[static_cast<size_t>(h.anchor)].pose, inverse(dr));
    }
    // Two hypotheses re-anchored on one experience are one: the better stays.
    std::stable_sort(hyps_.begin(), hyps_.end(), [](const Hypothesis& a, const Hypothesis& b) { return a.score > b.score; });
    std::vector<Hypothesis> kept;
    kept.reserve(hyps_.size() + candidates.size());
    for (const Hypothesis& h : hyps_) {
      if (h.score <= params_.drop_score && !h.prior) continue;
      const auto twin = h.anchor < 0 ? kept.end() : std::find_if(kept.begin(), kept.end(), [&](const Hypothesis& k) {
                                                     return k.anchor == h.anchor;
                                                   });
      if (twin == kept.end()) {
        kept.push_back(h);
      } else {
        twin->prior = twin->prior || h.prior;  // the same place: the prior is still among the hypotheses
      }
    }
    for (size_t k = 0; k < candidates.size(); ++k) {
      const int id = candidates[k];
      if (used[k] || id >= evidence_below_) continue;
      kept.push_back({compose(exps[static_cast<size_t>(id)].pose, inverse(dr)), id, 1, false});
    }
    // Bounded: the best max_hypotheses (stable: among equals the older first, then by experience).
    std::stable_sort(kept.begin(), kept.end(), [](const Hypothesis& a, const Hypothesis& b) { return a.score > b.score; });
    if (static_cast<int>(kept.size()) > params_.max_hypotheses) {
      const auto prior = std::find_if(kept.begin(), kept.end(), [](const Hypothesis& h) { return h.prior; });
      const auto last = kept.begin() + (params_.max_hypotheses - 1);
      if (prior != kept.end() && prior > last) std::rotate(last, prior, prior + 1);  // the prior is never crowded out
      kept.resize(static_cast<size_t>(params_.max_hypotheses));
    }
    hyps_ = std::move(kept);
    if (auto c = commit_if_ahead(map)) return c;
  }
  if (localising_m_ >= params_.give_up_m) {
    const auto prior = std::find_if(hyps_.begin(), hyps_.end(), [](const Hypothesis& h) { return h.prior; });
    if (prior != hyps_.end()) return commit(*prior, map, true);
  }
  return std::nullopt;
}

std::optional<Commit> Localiser::commit_if_ahead(const ExperienceMap& map) {
  if (hyps_.empty()) return std::nullopt;
  const Pose2 dr = map.current_pose();
  // hyps_ is sorted by score: the first is the best (the older among equals).
  const Hypothesis& best = hyps_.front();
  if (best.score < params_.commit_score || best.anchor < 0) return std::nullopt;
  const Pose2 pb = pose_of(best, dr);
  int rival = std::numeric_limits<int>::min();
  for (size_t i = 1; i < hyps_.size(); ++i) {
    const Pose2 p = pose_of(hyps_[i], dr);
    if (std::hypot(p.x - pb.x, p.y - pb.y) > params_.radius) rival = std::max(rival, hyps_[i].score);
  }
  if (rival != std::numeric_limits<int>::min() && best.score - rival < params_.commit_margin) return std::nullopt;
  return commit(best, map, false);
}

Commit Localiser::commit(const Hypothesis& h, const ExperienceMap& map, bool gave_up) {
  const Pose2 dr = map.current_pose();
  Commit c;
  c.gave_up = gave_up;
  c.experience = h.anchor >= 0 ? h.anchor : map.current_id();
  const Pose2 here = pose_of(h, dr);
  c.offset = c.experience >= 0 ? between(map.experiences()[static_cast<size_t>(c.experience)].pose, here) : here;
  if (!h.prior) {
    c.retire_from = std::min(evidence_below_, map.size());
    c.retire_to = map.size();
  }
  state_ = LocalisationState::Tracking;
  hyps_.clear();
  recent_.clear();
  localising_m_ = 0.0;
  count(localisations_);
  return c;
}

void Localiser::serialise(std::vector<uint8_t>& out) const {
  bin::put<uint8_t>(out, static_cast<uint8_t>(state_));
  bin::put<uint32_t>(out, static_cast<uint32_t>(recent_.size()));
  for (const TrackedRecognition& r : recent_) {
    bin::put<uint8_t>(out, r.refused ? 1 : 0);
    bin::put<int32_t>(out, r.first_new_id);
  }
  bin::put<int32_t>(out, evidence_below_);
  bin::put<double>(out, localising_m_);
  bin::put<int64_t>(out, kidnaps_detected_);
  bin::put<int64_t>(out, localisations_);
  bin::put<uint64_t>(out, hyps_.size());
  for (const Hypothesis& h : hyps_) {
    bin::put<double>(out, h.correction.x);
    bin::put<double>(out, h.correction.y);
    bin::put<double>(out, h.correction.theta);
    bin::put<int32_t>(out, h.anchor);
    bin::put<int32_t>(out, h.score);
    bin::put<uint8_t>(out, h.prior ? 1 : 0);
  }
}

void Localiser::deserialise(const std::vector<uint8_t>& in, size_t& pos, int num_experiences) {
  Localiser l(params_);
  const auto state = bin::get<uint8_t>(in, pos);
  if (state > static_cast<uint8_t>(LocalisationState::Localising)) throw std::runtime_error("checkpoint: bad localisation state");
  l.state_ = static_cast<LocalisationState>(state);
  const auto recent = bin::get<uint32_t>(in, pos);
  if (recent > in.size()) throw std::runtime_error("checkpoint: recognition count is larger than the data");
  for (uint32_t i = 0; i < recent; ++i) {
    TrackedRecognition r;
    r.refused = bin::get<uint8_t>(in, pos) != 0;
    r.first_new_id = bin::get<int32_t>(in, pos);
    if (r.first_new_id < 0) throw std::runtime_error("checkpoint: bad recognition record");
    l.recent_.push_back(r);
  }
  l.evidence_below_ = bin::get<int32_t>(in, pos);
  l.localising_m_ = bin::get<double>(in, pos);
  l.kidnaps_detected_ = bin::get<int64_t>(in, pos);
  l.localisations_ = bin::get<int64_t>(in, pos);
  if (l.evidence_below_ < 0 || !std::isfinite(l.localising_m_) || l.localising_m_ < 0.0 || l.kidnaps_detected_ < 0 ||
      l.localisations_ < 0) {
    throw std::runtime_error("checkpoint: bad localisation counters");
  }
  const auto n = bin::get<uint64_t>(in, pos);
  if (n > in.size()) throw std::runtime_error("checkpoint: hypothesis count is larger than the data");
  for (uint64_t i = 0; i < n; ++i) {
    Hypothesis h;
    h.correction.x = bin::get<double>(in, pos);
    h.correction.y = bin::get<double>(in, pos);
    h.correction.theta = bin::get<double>(in, pos);
    h.anchor = bin::get<int32_t>(in, pos);
    h.score = bin::get<int32_t>(in, pos);
    h.prior = bin::get<uint8_t>(in, pos) != 0;
    if (!std::isfinite(h.correction.x) || !std::isfinite(h.correction.y) || !std::isfinite(h.correction.theta) ||
        h.anchor < -1 || h.anchor >= num_experiences) {
      throw std::runtime_error("checkpoint: hypothesis " + std::to_string(i) + " is not finite or names no experience");
    }
    l.hyps_.push_back(h);
  }
  *this = std::move(l);
}

}  // namespace whiskeye::slam
