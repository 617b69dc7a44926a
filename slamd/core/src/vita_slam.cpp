// ViTa-SLAM cycle (Algorithm 1) and checkpoints. See vita_slam.h.
#include "whiskeye/slam/vita_slam.h"

#include "whiskeye/common/odometry_limits.h"

#include "binary_io.h"
#include "counters.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <optional>
#include <stdexcept>

namespace whiskeye::slam {

namespace {

constexpr char kMagic[8] = {'V', 'I', 'T', 'A', 'S', 'L', 'A', 'M'};
constexpr uint32_t kOldestReadable = 1;

uint32_t fnv1a(const uint8_t* data, size_t n) {
  uint32_t h = 2166136261u;
  for (size_t i = 0; i < n; ++i) {
    h ^= data[i];
    h *= 16777619u;
  }
  return h;
}

}  // namespace

VitaSlam::VitaSlam(const SlamParams& params, const RobotGeometry& geometry)
    : params_(params),
      geometry_(geometry),
      store_(params.visual.template_width, params.visual.template_height),
      cells_(params.pose_cells),
      map_(params.experience_map),
      localiser_(params.localisation) {}

void VitaSlam::start_localising(bool with_prior) {
  if (map_.size() == 0) return;
  // Where the robot was left is a candidate without a head start: after a long gap it may have been
  // carried anywhere, and a look-alike near where it was left must not commit at once (with the
  // kidnap's head start, one did: 11 false localisations where --map localised after 9 cycles).
  localiser_.start(with_prior && map_.current_id() >= 0, 0, map_.size());
}

// The match threshold for the terms in use: a visual-only ε and a three-term ε differ in scale.
double VitaSlam::tau_of(const Terms& terms) const {
  return terms.visual && terms.tactile ? params_.match.threshold_vita
         : terms.visual               ? params_.match.threshold_visual
                                      : params_.match.threshold_tactile;
}

// One cycle in the four steps of vita_slam.h, each a member function below.
CycleResult VitaSlam::process_cycle(const CycleInput& in) {
  CycleResult out;
  count(stats_.cycles);
  if (resume_gap_s_ && !in.odometry.empty()) {
    const double gap_s = (static_cast<double>(in.odometry.front().utime) - static_cast<double>(last_odometry_utime_)) * 1e-6;
    // A checkpoint written while localising goes on as it was: restarting would give a saved map a
    // prior, and make the experiences mapped before a kidnap's detection evidence again.
    const bool moved = !have_odometry_time_ || gap_s < 0.0 || gap_s > *resume_gap_s_;
    if (moved && !localiser_.localising()) start_localising(true);
    resume_gap_s_.reset();
  }
  integrate_odometry(in.odometry);                           // 1. path integration
  const CycleTemplates templates = make_templates(in, out);  // 2. templates of this cycle
  PoseCellBest pc = match_or_create(templates, out);         // 3. match or create
  update_map(in.utime, templates, pc, out);                  // 4. experience map
  return out;
}

// 1. Path integration. The experience map integrates every sample; the pose cells take one step
// per `path_integration_period` with the mean velocity of the samples in it, and the remainder is
// flushed at the cycle's end so that templates are matched against an up-to-date packet.
void VitaSlam::integrate_odometry(const std::vector<OdometrySample>& odometry) {
  double acc_vx = 0.0, acc_vy = 0.0, acc_omega = 0.0, acc_dt = 0.0;
  cycle_travel_m_ = 0.0;
  auto flush = [&] {
    if (acc_dt > 0.0) cells_.step(acc_vx / acc_dt, acc_vy / acc_dt, acc_omega / acc_dt, acc_dt);
    acc_vx = acc_vy = acc_omega = acc_dt = 0.0;
  };
  for (const OdometrySample& o : odometry) {
    // A sample no base can produce is skipped before it takes the clock: the next good one
    // integrates the whole interval (and the pose cells' sub-steps stay bounded).
    const bool usable = std::isfinite(o.vx) && std::isfinite(o.vy) && std::isfinite(o.omega) &&
                        std::hypot(o.vx, o.vy) <= kMaxOdometrySpeed && std::abs(o.omega) <= kMaxOdometryTurnRate;
    if (!usable) {
      count(stats_.odometry_rejected);
      continue;
    }
    if (have_odometry_time_ && o.utime < last_odometry_utime_) {
      // A little older: reordered, skipped. Older by more than a gap: the clock was stepped back
      // (and the daemon followed it), so integration goes on from this sample's time, counted as a
      // gap; its own interval is unknown and not integrated. Skipping it would stop path integration
      // for as long as the step, even across a restart from a checkpoint.
      const double back_s = (static_cast<double>(last_odometry_utime_) - static_cast<double>(o.utime)) * 1e-6;
      if (back_s <= params_.max_odometry_dt) {
        count(stats_.odometry_rejected);
        continue;
      }
      count(stats_.odometry_gaps);
      have_odometry_time_ = false;
    }
    double dt = 0.0;
    if (have_odometry_time_) {
      dt = static_cast<double>(o.utime - last_odometry_utime_) * 1e-6;
      if (dt > params_.max_odometry_dt) {
        count(stats_.odometry_gaps);
        dt = params_.max_odometry_dt;
      }
    }
    have_odometry_time_ = true;
    last_odometry_utime_ = o.utime;
    map_.integrate(o.vx, o.vy, o.omega, dt);
    cycle_travel_m_ += std::hypot(o.vx, o.vy) * dt;
    if (dt <= 0.0) continue;
    acc_vx += o.vx * dt;
    acc_vy += o.vy * dt;
    acc_omega += o.omega * dt;
    acc_dt += dt;
    if (acc_dt >= params_.path_integration_period) flush();
  }
  flush();
}

// 2. Templates of this cycle: visual and tactile, as the mode and the inputs allow; a refused
// frame or an empty whisk cycle is counted and reported in `out`, and the cycle goes on without it.
VitaSlam::CycleTemplates VitaSlam::make_templates(const CycleInput& in, CycleResult& out) {
  CycleTemplates t;
  if (uses_visual(params_.mode) && in.image != nullptr) {
    try {
      t.visual = make_visual_template(*in.image, params_.visual, decoder_ ? &*decoder_ : nullptr);
    } catch (const InputError& e) {
      count(stats_.bad_images);
      out.image_warning = e.what();
    }
  }
  if (uses_tactile(params_.mode) && in.whisk != nullptr) {
    const bool any_valid =
        std::any_of(in.whisk->samples.begin(), in.whisk->samples.end(), [](const WhiskSample& s) { return s.valid; });
    if (any_valid) {
      t.tactile = make_tactile_template(*in.whisk, geometry_, params_.tactile);
    } else {
      count(stats_.empty_whisk_cycles);
      out.whisk_warning = "whisk cycle " + std::to_string(in.whisk->cycle) + " has no valid sample";
    }
  }
  t.terms = Terms{t.visual.has_value(), t.tactile.has_value()};
  // ViTa with both senses: the fusion's rules (MatchParams::tactile_veto). A cycle that touched
  // nothing is decided by vision, with the visual threshold, among the templates touch does not
  // object to: those that touched nothing either, or barely (an empty touch is 1/σ_PFH from any
  // contact of three whiskers or more). Touch alone (tactile mode) compares empty touches, and is
  // fooled by them, as the paper's.
  t.terms.fused = params_.mode == Mode::Vita && t.terms.visual && t.terms.tactile;
  // ViTa without one of its senses (no usable frame, or no valid whisker sample): degraded, and a
  // missing sense never counts as a match. Vision alone may recognise a known template (with the
  // gate it closes no false loop), touch alone never: it is aliased by design (two boxes feel
  // alike), and a run of touches matching the twin box would move the estimate there. Either way
  // the cycle stores no template, injects no energy and creates no experience (update_map).
  out.degraded = params_.mode == Mode::Vita && t.terms.visual != t.terms.tactile;
  if (out.degraded) t.terms.tactile = false;
  out.dense = t.tactile.has_value() && t.tactile->has_contact();
  return t;
}

// 3. Match against every stored template, or create one; injects energy at a matched template's
// pose cells. Returns the pose cells' best estimate after it.
VitaSlam::PoseCellBest VitaSlam::match_or_create(const CycleTemplates& t, CycleResult& out) {
  const Query q{t.visual ? &*t.visual : nullptr, t.tactile ? &*t.tactile : nullptr};
  const Terms& terms = t.terms;
  PoseCellBest pc;
  cells_.best(pc.x, pc.y, pc.theta);
  store_.restore_decay(params_.pose_cells.vt_restore, 0.0);
  MatchResult& m = out.match;
  m.visual_used = terms.visual;
  m.tactile_used = terms.tactile;
  if (terms.visual || terms.tactile) {
    const BestMatch b = store_.match(q, terms, params_.match);
    const double tau = tau_of(terms);
    if (b.id >= 0) {
      m.error = b.error;
      m.visual_error = b.visual;
      m.pfh_error = b.pfh;
      m.sda_error = b.sda;
      m.visual_shift = b.shift;
    }
    if (b.id >= 0 && b.error <= tau) {
      m.template_id = b.id;
      m.is_new = false;
      // Recognised, but not to be learnt from: a degraded cycle's, or one while the place is
      // unknown (the packet's position means nothing until a localisation commits).
      if (out.degraded || localiser_.localising()) return pc;
      store_.bump_decay(b.id, params_.pose_cells.vt_active_decay);
      if (b.id < store_.size() - params_.pose_cells.inject_exclude_newest) {
        const double energy = params_.pose_cells.inject_energy *
                              std::max(0.0, 30.0 - std::exp(1.2 * store_.decay(b.id))) / 30.0;
        cells_.inject(store_.pc_x(b.id), store_.pc_y(b.id), store_.pc_theta(b.id), energy);
        for (int i = 0; i < params_.pose_cells.settle_steps; ++i) cells_.settle();
        cells_.best(pc.x, pc.y, pc.theta);
      }
    } else if (!localise_only_ && !out.degraded && (!localiser_.localising() || localiser_.learning())) {
      m.template_id = store_.add(q, pc.x, pc.y, pc.theta);
      m.is_new = true;
    }
  }
  return pc;
}

// 4. The experience map's action rule and relaxation, and the cycle's outputs.
void VitaSlam::update_map(int64_t utime, const CycleTemplates& templates, PoseCellBest& pc, CycleResult& out) {
  const MatchResult& m = out.match;
  const int tid = m.template_id;
  const int recognised = tid >= 0 && !m.is_new ? tid : -1;
  if (localiser_.localising()) {
    localise(utime, recognised, templates, pc, out);
  } else {
    const MapCycle cycle = map_cycle(tid, utime, pc, m.visual_used && !m.is_new ? m.visual_shift : 0, out);
    const MapDecision decision = map_.decide(cycle, cells_);
    // What the robot sees stopped agreeing with where it thinks it is: localise, this recognition
    // the first evidence, instead of acting on it (what the map would have made here was made where
    // the robot only thought it was).
    if (localiser_.on_tracking_recognition(decision.gate_refused, recognised, map_.size(), map_)) {
      localise(utime, recognised, templates, pc, out);
    } else {
      out.event = map_.act(decision, cycle);
      // A re-localisation the map accepted beyond the packet's reach (the pose cells drifted with
      // the odometry): the packet follows the map, so that what is recognised next is looked for there.
      if (out.event.type == EventType::Relocalise && out.event.to_id >= 0) move_packet_to(out.event.to_id, pc);
      if (wrong_closures_ && !localise_only_) wrong_closures_->on_cycle(out.event, map_, utime);
    }
  }
  out.localising = localiser_.localising();
  out.hypotheses = localiser_.hypotheses();
  out.experience_id = map_.current_id();
  out.pose = map_.current_pose();
  out.pc_x = pc.x;
  out.pc_y = pc.y;
  out.pc_theta = pc.theta;
  out.num_templates = store_.size();
}

// One cycle while localising: the recognition weighs the hypotheses; a commit moves the map's
// current experience (no link: the odometry since the last one says nothing about the way there)
// and the packet there. Until then the map stays where it was.
void VitaSlam::localise(int64_t utime, int recognised, const CycleTemplates& t, PoseCellBest& pc, CycleResult& out) {
  // With where odometry says as a candidate, a new place is mapped on from there tentatively (a
  // false alarm loses nothing; a kidnap's are retired when another place wins).
  const int from = map_.current_id();
  out.event = {EventType::SameExperience, from, from};
  if (localiser_.learning() && out.match.is_new && !localise_only_) {
    out.event = map_.on_cycle(map_cycle(out.match.template_id, utime, pc, 0, out), cells_);
  }
  // The view may be recognised as several templates (look-alikes learnt at other passes): any of
  // them is evidence for a place that holds it.
  const TemplateStore::Recogniser recognises(store_, Query{t.visual ? &*t.visual : nullptr, t.tactile ? &*t.tactile : nullptr},
                                             t.terms, params_.match, tau_of(t.terms));
  const std::optional<Commit> c =
      localiser_.on_localising_cycle(recognised, cycle_travel_m_, map_, [&](int id) { return recognises(id); });
  if (!c) return;
  const int before = map_.current_id();
  map_.jump_to(c->experience, c->offset);
  map_.retire(c->retire_from, c->retire_to);
  if (c->experience != before) out.event = {EventType::Relocalise, before, c->experience};
  if (c->experience >= 0) move_packet_to(c->experience, pc);
}

MapCycle VitaSlam::map_cycle(int template_id, int64_t utime, const PoseCellBest& pc, int view_shift,
                             const CycleResult& out) const {
  MapCycle c;
  c.template_id = template_id;
  c.visual_template_id = template_id >= 0 && store_.has_visual(template_id) ? template_id : -1;
  c.tactile_template_id = template_id >= 0 && store_.has_tactile(template_id) ? template_id : -1;
  c.dense = out.dense;
  c.pc_x = pc.x;
  c.pc_y = pc.y;
  c.pc_theta = pc.theta;
  c.utime = utime;
  c.view_shift = view_shift;
  c.degraded = out.degraded;
  return c;
}

void VitaSlam::move_packet_to(int experience, PoseCellBest& pc) {
  const Experience& e = map_.experiences()[static_cast<size_t>(experience)];
  if (cells_.distance(e.pc_x, e.pc_y, e.pc_theta, pc.x, pc.y, pc.theta) > params_.experience_map.delta_pc_threshold) {
    cells_.relocate(e.pc_x, e.pc_y, e.pc_theta);
    cells_.best(pc.x, pc.y, pc.theta);
  }
}

Pose2 VitaSlam::dead_reckon(const Pose2& offset) const { return compose(map_.current_pose(), offset); }

std::vector<uint8_t> VitaSlam::serialise() const {
  std::vector<uint8_t> out = serialise_unsealed();
  seal(out);
  return out;
}

void VitaSlam::seal(std::vector<uint8_t>& blob) { bin::put<uint32_t>(blob, fnv1a(blob.data(), blob.size())); }

std::vector<uint8_t> VitaSlam::serialise_unsealed() const {
  // Reserved once (the templates are nearly all of it; pose cells and map estimated generously),
  // so the copy is not reallocated on the way: ~30 MB at 10,000 templates.
  std::vector<uint8_t> out;
  out.reserve(4096 + store_.serialised_bytes() + 4 * sizeof(float) * cells_.activity().size() +
              128 * static_cast<size_t>(map_.size()) + 64 * map_.links().size() + sizeof(uint32_t));
  out.insert(out.end(), kMagic, kMagic + 8);
  bin::put<uint32_t>(out, kCheckpointFormat);
  bin::put<uint8_t>(out, static_cast<uint8_t>(params_.mode));
  bin::put<int64_t>(out, last_odometry_utime_);
  bin::put<uint8_t>(out, have_odometry_time_ ? 1 : 0);
  bin::put<int64_t>(out, stats_.cycles);
  bin::put<int64_t>(out, stats_.bad_images);
  bin::put<int64_t>(out, stats_.empty_whisk_cycles);
  bin::put<int64_t>(out, stats_.odometry_rejected);
  bin::put<int64_t>(out, stats_.odometry_gaps);
  store_.serialise(out);
  cells_.serialise(out);
  map_.serialise(out);
  localiser_.serialise(out);
  return out;
}

VitaSlam VitaSlam::deserialise(std::span<const uint8_t> data, const SlamParams& params,
                               const RobotGeometry& geometry) {
  const std::vector<uint8_t> in(data.begin(), data.end());
  if (in.size() < 8 + 4 + 4 || std::memcmp(in.data(), kMagic, 8) != 0) {
    throw std::runtime_error("checkpoint: not a ViTa-SLAM checkpoint (bad magic)");
  }
  size_t end = in.size() - 4;
  size_t tail = end;
  if (bin::get<uint32_t>(in, tail) != fnv1a(in.data(), end)) throw std::runtime_error("checkpoint: checksum mismatch");
  size_t pos = 8;
  const auto version = bin::get<uint32_t>(in, pos);
  if (version < kOldestReadable || version > kCheckpointFormat) {
    throw std::runtime_error("checkpoint: version " + std::to_string(version) + " unsupported (this build reads " +
                             std::to_string(kOldestReadable) + " to " + std::to_string(kCheckpointFormat) + ")");
  }
  const auto mode = bin::get<uint8_t>(in, pos);
  if (mode != static_cast<uint8_t>(params.mode)) {
    throw std::runtime_error("checkpoint: written in another mode than '" + to_string(params.mode) + "'");
  }
  VitaSlam s(params, geometry);
  s.last_odometry_utime_ = bin::get<int64_t>(in, pos);
  s.have_odometry_time_ = bin::get<uint8_t>(in, pos) != 0;
  s.stats_.cycles = bin::get<int64_t>(in, pos);
  s.stats_.bad_images = bin::get<int64_t>(in, pos);
  s.stats_.empty_whisk_cycles = bin::get<int64_t>(in, pos);
  s.stats_.odometry_rejected = bin::get<int64_t>(in, pos);
  s.stats_.odometry_gaps = bin::get<int64_t>(in, pos);
  for (const int64_t c : {s.stats_.cycles, s.stats_.bad_images, s.stats_.empty_whisk_cycles, s.stats_.odometry_rejected,
                          s.stats_.odometry_gaps}) {
    if (c < 0) throw std::runtime_error("checkpoint: a negative cycle or input counter");
  }
  s.store_ = TemplateStore::deserialise(in, pos, params.visual.template_width, params.visual.template_height, version);
  s.cells_.deserialise(in, pos);
  s.map_.deserialise(in, pos, version, s.store_.size());
  if (version >= 4) s.localiser_.deserialise(in, pos, s.map_.size());
  if (pos != end) throw std::runtime_error("checkpoint: " + std::to_string(end - pos) + " unexpected trailing bytes");
  return s;
}

}  // namespace whiskeye::slam
