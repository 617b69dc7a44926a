// Experience map: action rule and relaxation. See experience_map.h.
#include "whiskeye/slam/experience_map.h"

#include "binary_io.h"
#include "whiskeye/slam/pose_cells.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

namespace whiskeye::slam {

void load(const ParamNode& n, ExperienceMapParams& p) {
  n.get("delta_pc_threshold", p.delta_pc_threshold, 0.0, 1000.0);
  // Each end of a link moves by correction × its error: one loop removes 2 × correction of a lone
  // link's error, so above 0.5 it overshoots, and at 1 a pair swings between ±error for ever.
  n.get("correction", p.correction, 0.0, 0.5);
  n.get("loops", p.loops, 0, 10000);
  n.get("max_view_shift", p.max_view_shift, 0, 1000);
  n.get("max_view_shift_distinct", p.max_view_shift_distinct, 0, 1000);
  n.get("distinct_places", p.distinct_places, 0, 1000000);
  n.get("drift_base", p.drift_base, 0.0, 1000.0);
  n.get("drift_per_m", p.drift_per_m, 0.0, 1000.0);
  n.get("packet_trust_m", p.packet_trust_m, 0.0, 1e6);
  n.get("odometry_sigma_per_m", p.odometry_sigma_per_m, 0.0, 1.0);
  // A floor: without it a link of no length would have no σ and an infinite weight.
  n.get("odometry_sigma_min_m", p.odometry_sigma_min_m, 1e-6, 1.0);
  n.get("place_sigma_m", p.place_sigma_m, 0.0, 10.0);
  n.get("robust_phi", p.robust_phi, 0.0, 1e6);
}

namespace {

// A robust link's scale s² for its squared position residual r2 (m²), weight 1/σ² `w`, gate² and DCS's Φ:
// beyond its gate, no pull (the map disagrees with it: were it pulled at all, a ring of odometry as
// soft as a robot's would give way to it over the loops); within, dynamic covariance scaling
// s = min(1, 2Φ / (Φ + χ²)), χ² = r2 · w.
inline double robust_scale(double r2, double w, double gate2, double phi) {
  const double chi2 = r2 * w;
  const double sc = r2 > gate2 ? 0.0 : chi2 <= phi ? 1.0 : 2.0 * phi / (phi + chi2);
  return sc * sc;
}

}  // namespace

ExperienceMap::ExperienceMap(const ExperienceMapParams& params) : params_(params) {}

void ExperienceMap::set_params(const ExperienceMapParams& p) {
  params_ = p;
  for (size_t l = 0; l < links_.size(); ++l) {
    links_[l].sigma2 = link_sigma2(links_[l].delta, links_[l].recognised_ends);
    lw_[l] = 1.0 / links_[l].sigma2;
    lrobust_[l] = links_[l].recognised_ends > 0 && params_.robust_phi > 0.0 ? 1 : 0;
    if (lrobust_[l] == 0) lscale_[l] = links_[l].scale = 1.0;
  }
}

const std::vector<Experience>& ExperienceMap::experiences() const {
  sync_poses();
  return meta_;
}

void ExperienceMap::sync_poses() const {
  if (!poses_dirty_) return;
  for (size_t i = 0; i < meta_.size(); ++i) meta_[i].pose = {x_[i], y_[i], std::atan2(s_[i], c_[i])};
  poses_dirty_ = false;
}

Pose2 ExperienceMap::current_pose() const {
  if (current_ < 0) return offset_;
  const auto i = static_cast<size_t>(current_);
  return compose(Pose2{x_[i], y_[i], std::atan2(s_[i], c_[i])}, offset_);
}

void ExperienceMap::integrate(double vx, double vy, double omega, double dt) {
  offset_ = integrate_body_velocity(offset_, vx, vy, omega, dt);
  travel_ += std::hypot(vx, vy) * dt;
}

int ExperienceMap::add_experience(const Pose2& pose, const Experience& meta) {
  sync_poses();
  Experience e = meta;
  e.id = size();
  e.pose = pose;
  meta_.push_back(e);
  x_.push_back(pose.x);
  y_.push_back(pose.y);
  c_.push_back(std::cos(pose.theta));
  s_.push_back(std::sin(pose.theta));
  if (e.template_id >= 0 && !e.retired) {
    if (static_cast<size_t>(e.template_id) >= by_template_.size()) by_template_.resize(static_cast<size_t>(e.template_id) + 1);
    by_template_[static_cast<size_t>(e.template_id)].push_back(e.id);
  }
  return e.id;
}

double ExperienceMap::link_sigma2(const Pose2& delta, int recognised_ends) const {
  const double odometry = std::max(params_.odometry_sigma_min_m, params_.odometry_sigma_per_m * std::hypot(delta.x, delta.y));
  return odometry * odometry + recognised_ends * params_.place_sigma_m * params_.place_sigma_m;
}

void ExperienceMap::add_link(int from, int to, const Pose2& delta, int64_t utime, int recognised_ends, double gate_m) {
  if (from < 0 || to < 0 || from >= size() || to >= size() || from == to) {
    throw std::invalid_argument("ExperienceMap::add_link: bad ends " + std::to_string(from) + " -> " + std::to_string(to));
  }
  if (recognised_ends < 0 || recognised_ends > 2) {
    throw std::invalid_argument("ExperienceMap::add_link: " + std::to_string(recognised_ends) + " recognised ends");
  }
  if (!(gate_m > 0.0)) throw std::invalid_argument("ExperienceMap::add_link: gate " + std::to_string(gate_m) + " m");
  const double sigma2 = link_sigma2(delta, recognised_ends);
  links_.push_back({from, to, delta, utime, recognised_ends, sigma2, 1.0, gate_m});
  lgate2_.push_back(gate_m * gate_m);
  lfrom_.push_back(from);
  lto_.push_back(to);
  ldx_.push_back(delta.x);
  ldy_.push_back(delta.y);
  ldc_.push_back(std::cos(delta.theta));
  lds_.push_back(std::sin(delta.theta));
  lw_.push_back(1.0 / sigma2);
  lrobust_.push_back(recognised_ends > 0 && params_.robust_phi > 0.0 ? 1 : 0);
  lscale_.push_back(1.0);
  if (lrobust_.back() != 0) {
    // Judged at once, as the next relaxation would: a map published before then shows it as it stands.
    const auto a = static_cast<size_t>(from), b = static_cast<size_t>(to);
    const double ex = x_[b] - (x_[a] + c_[a] * delta.x - s_[a] * delta.y);
    const double ey = y_[b] - (y_[a] + s_[a] * delta.x + c_[a] * delta.y);
    lscale_.back() = links_.back().scale = robust_scale(ex * ex + ey * ey, lw_.back(), lgate2_.back(), params_.robust_phi);
  }
}

void ExperienceMap::set_current(int id, const Pose2& offset) {
  current_ = id;
  offset_ = offset;
  current_recognised_ = false;
}

bool ExperienceMap::link_current_to(int to, int64_t utime) {
  const int from = current_;
  if (from < 0 || to == from) return false;
  for (size_t l = 0; l < lfrom_.size(); ++l) {
    if ((lfrom_[l] == from && lto_[l] == to) || (lfrom_[l] == to && lto_[l] == from)) return false;
  }
  add_link(from, to, offset_, utime, 1 + (current_recognised_ ? 1 : 0), drift_budget());
  return true;
}

void ExperienceMap::jump_to(int id, const Pose2& offset) {
  if (id < -1 || id >= size()) throw std::invalid_argument("ExperienceMap::jump_to: no experience " + std::to_string(id));
  set_current(id, offset);
  current_recognised_ = true;
  travel_ = 0.0;
}

bool ExperienceMap::mapped_near(const Pose2& pose, double radius, double heading, int below_id) const {
  bool any = false;
  for_each_near(pose, radius, heading, below_id, [&](int, double) { return !(any = true); });
  return any;
}

void ExperienceMap::retire(int from_id, int to_id) {
  from_id = std::max(from_id, 0);
  to_id = std::min(to_id, size());
  for (int id = from_id; id < to_id; ++id) {
    Experience& e = meta_[static_cast<size_t>(id)];
    if (e.retired) continue;
    e.retired = true;
    if (e.template_id >= 0) std::erase(by_template_[static_cast<size_t>(e.template_id)], id);
  }
}

const std::vector<int>& ExperienceMap::experiences_of(int template_id) const {
  static const std::vector<int> kNone;
  return template_id >= 0 && static_cast<size_t>(template_id) < by_template_.size()
             ? by_template_[static_cast<size_t>(template_id)]
             : kNone;
}

namespace {

// Applies one loop's accumulated pulls to every node (a damped Jacobi step): positions move by
// f · (mean position error); headings turn by δ = f · (mean sin of the heading error), with the
// rotation (cos δ, sin δ) from its Taylor series (|δ| ≤ f ≤ 1; the error is < 3e-6 at δ = 1 and
// at rounding level for the small δ of a settled map). No sqrt, division or trig: the loop
// vectorises. A separate out-of-line function so the restrict guarantees survive; on x86-64 a
// second clone uses AVX2 (4 doubles per instruction, no FMA, so results are bit-identical to the
// SSE2 clone), chosen at load time.
#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__) && !defined(__SANITIZE_ADDRESS__)
__attribute__((target_clones("avx2", "default")))
#endif
__attribute__((noinline)) void apply_corrections(size_t n, double f, const double* __restrict inv,
                                                 double* __restrict x, double* __restrict y, double* __restrict c,
                                                 double* __restrict s, double* __restrict ax, double* __restrict ay,
                                                 double* __restrict as) {
  for (size_t i = 0; i < n; ++i) {
    const double k = f * inv[i];
    x[i] += k * ax[i];
    y[i] += k * ay[i];
    const double d = k * as[i];
    const double d2 = d * d;
    // Horner forms of cos and sin to d⁸ and d⁹, multiplying by constant reciprocals (a division
    // would not be turned into a multiplication without -freciprocal-math).
    constexpr double k2 = 1.0 / 2, k12 = 1.0 / 12, k30 = 1.0 / 30, k56 = 1.0 / 56;
    constexpr double k6 = 1.0 / 6, k20 = 1.0 / 20, k42 = 1.0 / 42, k72 = 1.0 / 72;
    const double cd = 1.0 - d2 * k2 * (1.0 - d2 * k12 * (1.0 - d2 * k30 * (1.0 - d2 * k56)));
    const double sd = d * (1.0 - d2 * k6 * (1.0 - d2 * k20 * (1.0 - d2 * k42 * (1.0 - d2 * k72))));
    const double nc = c[i] * cd - s[i] * sd;
    const double ns = s[i] * cd + c[i] * sd;
    c[i] = nc;
    s[i] = ns;
    ax[i] = 0.0;
    ay[i] = 0.0;
    as[i] = 0.0;
  }
}

}  // namespace

void ExperienceMap::relax(int loops) {
  const size_t n = x_.size();
  const size_t nl = lfrom_.size();
  if (nl == 0 || loops <= 0) return;
  ax_.assign(n, 0.0);
  ay_.assign(n, 0.0);
  as_.assign(n, 0.0);
  aw_.assign(n, 0.0);
  inv_.assign(n, 0.0);
  const double f = params_.correction;
  const double phi = params_.robust_phi;
  double* __restrict aw = aw_.data();
  double* __restrict scale = lscale_.data();
  const double* __restrict lw = lw_.data();
  const uint8_t* __restrict robust = lrobust_.data();
  const double* __restrict gate2 = lgate2_.data();
  double* __restrict x = x_.data();
  double* __restrict y = y_.data();
  double* __restrict c = c_.data();
  double* __restrict s = s_.data();
  double* __restrict ax = ax_.data();
  double* __restrict ay = ay_.data();
  double* __restrict as = as_.data();
  double* __restrict inv = inv_.data();
  for (int loop = 0; loop < loops; ++loop) {
    for (size_t l = 0; l < nl; ++l) {
      const auto a = static_cast<size_t>(lfrom_[l]);
      const auto b = static_cast<size_t>(lto_[l]);
      const double ca = c[a], sa = s[a];
      const double px = x[a] + ca * ldx_[l] - sa * ldy_[l];
      const double py = y[a] + sa * ldx_[l] + ca * ldy_[l];
      double ex = x[b] - px, ey = y[b] - py;
      if (robust[l] != 0) scale[l] = robust_scale(ex * ex + ey * ey, lw[l], gate2[l], phi);
      const double w = lw[l] * scale[l];
      ex *= w;
      ey *= w;
      ax[a] += ex;
      ay[a] += ey;
      ax[b] -= ex;
      ay[b] -= ey;
      aw[a] += w;
      aw[b] += w;
      // q = R_a·R_δ: the heading b should have.
      const double qc = ca * ldc_[l] - sa * lds_[l];
      const double qs = sa * ldc_[l] + ca * lds_[l];
      // sin of b's heading error ε = θ_b − (θ_a + δθ): a turns by +ε, b by −ε.
      const double es = w * (qc * s[b] - qs * c[b]);
      as[a] += es;
      as[b] -= es;
    }
    // A node's correction is the weighted mean over its links.
    for (size_t i = 0; i < n; ++i) {
      inv[i] = aw[i] > 0.0 ? 1.0 / aw[i] : 0.0;
      aw[i] = 0.0;
    }
    apply_corrections(n, f, inv, x, y, c, s, ax, ay, as);
  }
  for (size_t l = 0; l < nl; ++l) links_[l].scale = scale[l];
  // Products of unit complex numbers drift off the circle by rounding only; renormalise once.
  for (size_t i = 0; i < n; ++i) {
    const double k = 1.0 / std::sqrt(c[i] * c[i] + s[i] * s[i]);
    c[i] *= k;
    s[i] *= k;
  }
  poses_dirty_ = true;
}

MapDecision ExperienceMap::decide(const MapCycle& cycle, const PoseCells& cells) const {
  using Action = MapDecision::Action;
  MapDecision d;
  if (cycle.template_id < 0) return d;
  const std::vector<int>& candidates = experiences_of(cycle.template_id);
  if (candidates.empty()) {
    if (!frozen_ && !cycle.degraded) d.action = Action::Create;
    return d;
  }
  int nearest = -1;
  double dmin = 0.0;
  const int max_shift = static_cast<int>(candidates.size()) <= params_.distinct_places ? params_.max_view_shift_distinct
                                                                                      : params_.max_view_shift;
  // With the odometry-consistency gate on, only experiences within the drift budget in the map
  // count. While the robot recognised a place recently (travel ≤ packet_trust_m) the pose cells
  // choose among them, as in RatSLAM: the packet is where the views put it and resolves
  // neighbouring experiences better than the relaxed map. After a longer stretch without any,
  // the packet may have drifted away with the odometry: the nearest in the map is taken (and
  // VitaSlam moves the packet there). Frozen (localisation only): the same, whatever the view shift.
  const bool gate = params_.drift_per_m < 100.0;
  const bool by_map = gate && travel_ > params_.packet_trust_m;
  const Pose2 here = gate ? current_pose() : Pose2{};  // the map's distances only matter with the gate
  const double budget = drift_budget();
  // Refused by the gate alone: no experience of the template within the budget, whatever its view
  // shift (one within it seen from another pose is the same place), and one beyond it that the
  // view-shift rule would take (the view is that place's, seen as it was then).
  bool within_budget = !gate, refused_beyond = false;
  for (int id : candidates) {
    const Experience& e = meta_[static_cast<size_t>(id)];
    const auto i = static_cast<size_t>(id);
    const double dm = gate ? std::hypot(x_[i] - here.x, y_[i] - here.y) : 0.0;
    within_budget = within_budget || dm <= budget;
    if (!frozen_ && std::abs(cycle.view_shift - e.view_shift) > max_shift) continue;
    if (gate && dm > budget) {
      refused_beyond = true;
      continue;
    }
    const double dist = by_map ? dm : cells.distance(e.pc_x, e.pc_y, e.pc_theta, cycle.pc_x, cycle.pc_y, cycle.pc_theta);
    if (nearest < 0 || dist < dmin) {
      nearest = id;
      dmin = dist;
    }
  }
  const double limit = by_map ? budget : params_.delta_pc_threshold;
  // No candidate left by the view-shift rule (never when frozen, which ignores it), or none near.
  if (nearest < 0 || (dmin > limit && !frozen_)) {
    d.action = !cycle.degraded && !frozen_ ? Action::Create : Action::Unmatched;
    d.gate_refused = !within_budget && refused_beyond;
  } else {
    d.action = nearest != current_ ? Action::Relocalise : Action::Stay;
    d.target = nearest;
  }
  return d;
}

Event ExperienceMap::act(const MapDecision& decision, const MapCycle& cycle) {
  using Action = MapDecision::Action;
  Event ev;
  ev.type = EventType::SameExperience;
  ev.from_id = ev.to_id = current_;
  ev.gate_refused = decision.gate_refused;
  const int from = current_;
  switch (decision.action) {
    case Action::None:
      return ev;  // nothing to do, nor to relax
    case Action::Unmatched:
      break;
    case Action::Stay:
      travel_ = 0.0;  // recognised where it already is: as good as a re-localisation
      break;
    case Action::Create: {
      Experience meta;
      meta.pc_x = cycle.pc_x;
      meta.pc_y = cycle.pc_y;
      meta.pc_theta = cycle.pc_theta;
      meta.utime_created = cycle.utime;
      meta.template_id = cycle.template_id;
      meta.visual_template_id = cycle.visual_template_id;
      meta.tactile_template_id = cycle.tactile_template_id;
      meta.dense = cycle.dense;
      meta.view_shift = cycle.view_shift;
      const int id = add_experience(current_pose(), meta);
      if (from >= 0) {
        const double gate = current_recognised_ ? drift_budget() : std::numeric_limits<double>::infinity();
        add_link(from, id, offset_, cycle.utime, current_recognised_ ? 1 : 0, gate);
      }
      set_current(id);
      ev = {EventType::NewExperience, from, id, decision.gate_refused};
      break;
    }
    case Action::Relocalise:
      if (!frozen_) link_current_to(decision.target, cycle.utime);
      set_current(decision.target);
      current_recognised_ = true;
      travel_ = 0.0;
      ev = {EventType::Relocalise, from, decision.target};
      break;
  }
  if (!frozen_) relax(params_.loops);
  return ev;
}

void ExperienceMap::serialise(std::vector<uint8_t>& out) const {
  bin::put<uint64_t>(out, meta_.size());
  for (size_t i = 0; i < meta_.size(); ++i) {
    const Experience& e = meta_[i];
    bin::put<double>(out, x_[i]);
    bin::put<double>(out, y_[i]);
    bin::put<double>(out, c_[i]);
    bin::put<double>(out, s_[i]);
    bin::put<double>(out, e.pc_x);
    bin::put<double>(out, e.pc_y);
    bin::put<double>(out, e.pc_theta);
    bin::put<int64_t>(out, e.utime_created);
    bin::put<int32_t>(out, e.template_id);
    bin::put<int32_t>(out, e.visual_template_id);
    bin::put<int32_t>(out, e.tactile_template_id);
    bin::put<uint8_t>(out, e.dense ? 1 : 0);
    bin::put<int32_t>(out, e.view_shift);
    bin::put<uint8_t>(out, e.retired ? 1 : 0);
  }
  bin::put<uint64_t>(out, links_.size());
  for (size_t l = 0; l < links_.size(); ++l) {
    bin::put<int32_t>(out, links_[l].from);
    bin::put<int32_t>(out, links_[l].to);
    bin::put<double>(out, links_[l].delta.x);
    bin::put<double>(out, links_[l].delta.y);
    bin::put<double>(out, links_[l].delta.theta);
    bin::put<int64_t>(out, links_[l].utime_created);
    bin::put<uint8_t>(out, static_cast<uint8_t>(links_[l].recognised_ends));
    bin::put<double>(out, lscale_[l]);
    bin::put<double>(out, links_[l].gate_m);
  }
  bin::put<int32_t>(out, current_);
  bin::put<uint8_t>(out, current_recognised_ ? 1 : 0);
  bin::put<double>(out, offset_.x);
  bin::put<double>(out, offset_.y);
  bin::put<double>(out, offset_.theta);
  bin::put<double>(out, travel_);
}

void ExperienceMap::deserialise(const std::vector<uint8_t>& in, size_t& pos, uint32_t format_version,
                                int num_templates) {
  auto finite = [](std::initializer_list<double> values) {
    return std::all_of(values.begin(), values.end(), [](double v) { return std::isfinite(v); });
  };
  auto template_ok = [&](int id) { return id >= -1 && id < num_templates; };
  ExperienceMap m(params_);
  const auto n = bin::get<uint64_t>(in, pos);
  if (n > in.size()) throw std::runtime_error("checkpoint: experience count is larger than the data");
  for (uint64_t i = 0; i < n; ++i) {
    Experience e;
    const double x = bin::get<double>(in, pos), y = bin::get<double>(in, pos);
    const double c = bin::get<double>(in, pos), s = bin::get<double>(in, pos);
    e.pc_x = bin::get<double>(in, pos);
    e.pc_y = bin::get<double>(in, pos);
    e.pc_theta = bin::get<double>(in, pos);
    e.utime_created = bin::get<int64_t>(in, pos);
    e.template_id = bin::get<int32_t>(in, pos);
    e.visual_template_id = bin::get<int32_t>(in, pos);
    e.tactile_template_id = bin::get<int32_t>(in, pos);
    e.dense = bin::get<uint8_t>(in, pos) != 0;
    if (format_version >= 2) e.view_shift = bin::get<int32_t>(in, pos);
    if (format_version >= 4) e.retired = bin::get<uint8_t>(in, pos) != 0;
    for (const auto& [what, id] : {std::pair{"template", e.template_id}, std::pair{"visual template", e.visual_template_id},
                                   std::pair{"tactile template", e.tactile_template_id}}) {
      if (!template_ok(id)) {
        throw std::runtime_error("checkpoint: experience " + std::to_string(i) + " refers to " + what + " " +
                                 std::to_string(id) + " of " + std::to_string(num_templates));
      }
    }
    if (!finite({x, y, c, s, e.pc_x, e.pc_y, e.pc_theta}) || std::abs(c * c + s * s - 1.0) > 1e-6) {
      throw std::runtime_error("checkpoint: experience " + std::to_string(i) + " has a non-finite pose or heading");
    }
    if (std::abs(x) > kMaxMapExtent_m || std::abs(y) > kMaxMapExtent_m) {
      throw std::runtime_error("checkpoint: experience " + std::to_string(i) + " lies beyond " +
                               std::to_string(static_cast<int>(kMaxMapExtent_m)) + " m of the map's origin");
    }
    m.add_experience({x, y, std::atan2(s, c)}, e);
    // Restore the exact heading representation, not its round trip through an angle.
    m.c_.back() = c;
    m.s_.back() = s;
  }
  const auto nl = bin::get<uint64_t>(in, pos);
  if (nl > in.size()) throw std::runtime_error("checkpoint: link count is larger than the data");
  for (uint64_t l = 0; l < nl; ++l) {
    const int from = bin::get<int32_t>(in, pos), to = bin::get<int32_t>(in, pos);
    Pose2 d;
    d.x = bin::get<double>(in, pos);
    d.y = bin::get<double>(in, pos);
    d.theta = bin::get<double>(in, pos);
    const auto ut = bin::get<int64_t>(in, pos);
    if (!finite({d.x, d.y, d.theta})) throw std::runtime_error("checkpoint: link " + std::to_string(l) + " is not finite");
    if (std::hypot(d.x, d.y) > kMaxMapExtent_m) {
      throw std::runtime_error("checkpoint: link " + std::to_string(l) + " is longer than " +
                               std::to_string(static_cast<int>(kMaxMapExtent_m)) + " m");
    }
    int recognised = 0;
    double scale = 1.0;
    double gate = std::numeric_limits<double>::infinity();
    if (format_version >= 6) {
      recognised = bin::get<uint8_t>(in, pos);
      scale = bin::get<double>(in, pos);
      if (!std::isfinite(scale) || scale < 0.0 || scale > 1.0) {
        throw std::runtime_error("checkpoint: link " + std::to_string(l) + " has a scale outside [0, 1]");
      }
    }
    if (format_version >= 7) {
      gate = bin::get<double>(in, pos);
      if (!(gate > 0.0)) throw std::runtime_error("checkpoint: link " + std::to_string(l) + " has a gate that is not > 0");
    } else if (to >= 0 && to < m.size() && ut > m.meta_[static_cast<size_t>(to)].utime_created) {
      recognised = 1;  // made after its `to`: a re-localisation's link
    }
    try {
      m.add_link(from, to, d, ut, recognised, gate);
    } catch (const std::invalid_argument& e) {
      throw std::runtime_error(std::string("checkpoint: ") + e.what());
    }
    m.lscale_.back() = m.links_.back().scale = scale;
  }
  m.current_ = bin::get<int32_t>(in, pos);
  if (m.current_ < -1 || m.current_ >= m.size()) throw std::runtime_error("checkpoint: bad current experience");
  if (format_version >= 6) m.current_recognised_ = bin::get<uint8_t>(in, pos) != 0;
  m.offset_.x = bin::get<double>(in, pos);
  m.offset_.y = bin::get<double>(in, pos);
  m.offset_.theta = bin::get<double>(in, pos);
  // Version 3: the distance travelled since the last re-localisation (the drift budget's); older
  // checkpoints restart it at 0 (a tight budget until the robot has moved).
  if (format_version >= 3) {
    m.travel_ = bin::get<double>(in, pos);
    if (!std::isfinite(m.travel_) || m.travel_ < 0.0) throw std::runtime_error("checkpoint: bad travelled distance");
  }
  if (!finite({m.offset_.x, m.offset_.y, m.offset_.theta})) throw std::runtime_error("checkpoint: offset is not finite");
  m.poses_dirty_ = true;
  *this = std::move(m);
}

}  // namespace whiskeye::slam
