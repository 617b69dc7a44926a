// Experience map (RatSLAM): a graph of experiences (poses of the base in the map frame, each tied
// to a template and the pose-cell estimate at creation) linked by the odometry measured between
// them. Per cycle, the action rule decides between staying, creating an experience, or
// re-localising onto an existing one (a loop closure), and the graph is relaxed.
//
// Relaxation: each loop computes, for every link a→b, the error between b and a ∘ δ, and moves
// both ends towards agreement — positions by `correction`·error, headings by `correction`·sin of
// the heading error (equal to the error to first order, the right sign for any error below π) —
// a weighted mean over a node's links (damped Jacobi). A link's weight is its information, 1/σ²
// (ExperienceMapParams, "the back end"): an odometry measurement between two places where the robot
// was is precise; an end the robot only recognised (a re-localisation put it at that experience,
// up to half the experience spacing from where the experience was made) is not, and such a link is
// also robust: it has no pull while its residual exceeds the drift budget it was made within (a
// consistency test: the map disagrees with it), and within that, dynamic covariance scaling weakens it
// as the rest of the map disagrees with it.
// Headings are kept as unit complex numbers (cos, sin) and turned by multiplication with a
// Taylor-series rotation, so the loop needs no trigonometry or square root; arrays are contiguous
// (no pointer chasing).
#pragma once

#include "whiskeye/common/params.h"
#include "whiskeye/common/se2.h"
#include "whiskeye/slam/types.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

namespace whiskeye::slam {

class PoseCells;

struct ExperienceMapParams {
  double delta_pc_threshold = 1.0;  // cells: farther than this from every experience of the template → new
  double correction = 0.5;          // fraction of a link's error removed per loop
  int loops = 20;                   // relaxation loops per cycle
  // Template columns. The visual match's column shift measures how far the view is turned from
  // the template's (in the paper's arena 1 column ≈ 1.4°, ≈ 1.7 cm along the circle). Re-localising
  // onto an experience needs the shift to be within this of the shift that experience was created
  // with; a larger one is the same place seen from another pose: a new experience of the template.
  // A value ≥ match.shift_max turns the rule off.
  int max_view_shift = 2;
  // The same for a distinctive template: one with at most distinct_places experiences. A template
  // recognised at many places (a blank wall, a corner) is aliased and its shift poorly determined, so
  // it keeps the strict max_view_shift; a distinctive one may re-localise from a little farther.
  int max_view_shift_distinct = 4;
  int distinct_places = 2;
  // Odometry consistency (docs/slam-core.md, "Robust re-localisation"): a re-localisation may move
  // the pose estimate only as far as odometry can have drifted since the last one,
  //   budget = drift_base + drift_per_m · (distance travelled since the last re-localisation),
  // measured in the map (metres), so a look-alike place farther away — or one that the pose
  // cells' wrap-around puts nearby — is not closed onto. drift_per_m ≥ 100 turns the gate off:
  // then the pose cells alone decide, as in RatSLAM (the nearest in pose-cell space within
  // delta_pc_threshold).
  // Shipped on (0.15): without it a look-alike place metres away is closed onto whenever the pose
  // cells allow (docs/results.md has the suite's figures with and without it).
  double drift_base = 0.25;   // m
  double drift_per_m = 0.15;  // m per m travelled; ≥ 100 turns the gate off (the paper's scheme)
  // Within the budget, the pose cells choose (nearest in pose-cell space within
  // delta_pc_threshold) while the robot has re-localised within this distance travelled; after a
  // longer stretch without any, the nearest in the map (the packet may have drifted away).
  double packet_trust_m = 1.0;
  // The back end (docs/slam-core.md, "The back end: weighted, revocable links"). A link's σ² is
  //   max(odometry_sigma_min_m, odometry_sigma_per_m · its length)² + (recognised ends) · place_sigma_m²,
  // its weight 1/σ². A link with a recognised end is weighted further by dynamic covariance scaling
  // (Agarwal et al., ICRA 2013): s² with s = min(1, 2Φ / (Φ + χ²)), χ² = |position residual|² / σ²,
  // recomputed every relaxation loop, so that a closure the rest of the map disagrees with loses its
  // pull (revoked below kRevokedScale) and regains it if the map comes to agree. robust_phi 0 turns
  // the scaling off; odometry_sigma_per_m and place_sigma_m 0 weigh every link alike (RatSLAM's).
  // The σ's are those measured on the default arena's links against ground truth (2 cm on a 10 cm
  // link of odometry, 4.6 cm with a recognised end); Φ = 64 keeps the full pull up to 8 σ (0.3 m), so
  // that only a closure metres off is revoked: the first closures of a drifting loop are 0.2-0.3 m
  // off and must bend it (docs/results.md, "The back end").
  double odometry_sigma_per_m = 0.2;   // m per m of the link's length
  double odometry_sigma_min_m = 0.01;  // m: the σ of a link too short for the term above
  double place_sigma_m = 0.03;         // m: where a recognised place puts the robot, against where it is
  double robust_phi = 64.0;            // DCS's Φ: the χ² up to which a link keeps its whole pull
};
// A link's scale s² below this (its pull all but gone) is reported as revoked.
inline constexpr double kRevokedScale = 0.01;
// No map reaches this far from its origin, nor has a link this long (m; 10,000 km, days of driving at
// the fastest odometry slamd takes): a checkpoint that does is refused (one link of 1e300 m spread
// through the relaxation to every experience).
inline constexpr double kMaxMapExtent_m = 1e7;
void load(const ParamNode& node, ExperienceMapParams& p);

struct Experience {
  int id = -1;
  Pose2 pose;                 // base in the map frame
  double pc_x = 0.0, pc_y = 0.0, pc_theta = 0.0;  // pose-cell estimate at creation, cells
  int64_t utime_created = 0;
  int template_id = -1;
  int visual_template_id = -1;   // -1: the template has no visual part
  int tactile_template_id = -1;  // -1: no tactile part
  bool dense = false;            // tactile data present (contact) — the paper's dense node
  int view_shift = 0;            // column shift of the view against its template at creation
  // Made while the robot was lost (between a kidnap and its detection: localiser.h): where the map
  // puts it is not where it was seen. Kept in the graph for its links, never a candidate again.
  bool retired = false;
};

struct Link {
  int from = -1;
  int to = -1;
  Pose2 delta;  // pose of `to` in the frame of `from`, as measured by odometry
  int64_t utime_created = 0;
  // Ends the robot only recognised (0..2): `from` when the robot had re-localised onto it, `to`
  // when this link is a re-localisation's. A link with one is robust (ExperienceMapParams).
  int recognised_ends = 0;
  double sigma2 = 1.0;  // m²: the link's σ² (its weight is 1 / sigma2, times scale for a robust one)
  double scale = 1.0;   // DCS's s² after the last relaxation (1 for a link that is not robust)
  // m: a robust link whose position residual exceeds this is inconsistent with the map and has no
  // pull at all (scale 0) until the map comes within it again: the odometry-consistency gate's budget
  // when the link was made, which every closure the front end makes is within (infinite: no gate).
  double gate_m = std::numeric_limits<double>::infinity();
  bool revoked() const { return scale < kRevokedScale; }
};

// What one cycle brings the action rule (VitaSlam fills it). template_id < 0: no template this
// cycle (nothing to do). view_shift: the visual match's column shift (0 for a new template or
// without vision). degraded: the cycle lacked a sense its mode uses; it may re-localise onto an
// existing experience of the template by the usual rule, but never creates an experience or a link.
struct MapCycle {
  int template_id = -1;
  int visual_template_id = -1;   // -1: the template has no visual part
  int tactile_template_id = -1;  // -1: no tactile part
  bool dense = false;            // tactile data present (contact)
  double pc_x = 0.0, pc_y = 0.0, pc_theta = 0.0;  // the pose cells' best estimate, cells
  int64_t utime = 0;
  int view_shift = 0;
  bool degraded = false;
};

// What the action rule decided for a cycle (ExperienceMap::decide), not yet done.
struct MapDecision {
  enum class Action : uint8_t {
    None,        // no template this cycle, or a template the map has no experience of and may make none
    Unmatched,   // no experience of the template taken, and none may be made (degraded, frozen)
    Stay,        // recognised where the robot already is
    Create,      // a new experience (and the link to it)
    Relocalise,  // onto `target` (a loop closure)
  };
  Action action = Action::None;
  int target = -1;
  bool gate_refused = false;  // Event::gate_refused
};

class ExperienceMap {
 public:
  explicit ExperienceMap(const ExperienceMapParams& params = {});

  const std::vector<Experience>& experiences() const;  // poses as of the last relaxation
  const std::vector<Link>& links() const { return links_; }
  int current_id() const { return current_; }
  int size() const { return static_cast<int>(meta_.size()); }
  // Odometry since the current experience (or since the origin before the first one).
  const Pose2& offset() const { return offset_; }
  // Distance travelled (m) since the last re-localisation (or the start), and the budget it gives.
  double travel_since_relocalisation() const { return travel_; }
  double drift_budget() const { return params_.drift_base + params_.drift_per_m * travel_; }
  // current experience ∘ offset: the dead-reckoned pose of the base.
  Pose2 current_pose() const;

  void integrate(double vx, double vy, double omega, double dt);

  // The action rule for one cycle, decided, then carried out (on_cycle: both). Deciding changes
  // nothing, so that the caller may act otherwise on what it says (VitaSlam localises instead when
  // the decision's gate refusal reveals a kidnap).
  MapDecision decide(const MapCycle& cycle, const PoseCells& cells) const;
  // Carries out `decision` (decided on this map, unchanged since, for `cycle`): the experience made,
  // the link, the current experience moved; then the relaxation (not when frozen).
  Event act(const MapDecision& decision, const MapCycle& cycle);
  Event on_cycle(const MapCycle& cycle, const PoseCells& cells) { return act(decide(cycle, cells), cycle); }

  // Building blocks (public for tests and the benchmark).
  int add_experience(const Pose2& pose, const Experience& meta);
  // `recognised_ends`, `gate_m`: Link's; its σ² follows from the parameters.
  void add_link(int from, int to, const Pose2& delta, int64_t utime, int recognised_ends = 0,
                double gate_m = std::numeric_limits<double>::infinity());
  void set_current(int id, const Pose2& offset = {});
  // The link a re-localisation onto `to` makes: from the current experience, measured as the odometry
  // since it (the robot, at offset() from it, is at `to`), `to` a recognised end; none if the two are
  // linked already or there is no current experience (false). The current experience does not change.
  bool link_current_to(int to, int64_t utime);
  // Moves the base to `offset` from experience `id` without a link (the odometry since the current
  // experience says nothing about the way there: a localisation after a kidnap or a restart).
  void jump_to(int id, const Pose2& offset);
  // Whether the map has an experience within `radius` (m) of `pose`, turned at most `heading` (rad)
  // from it: whether the place has been mapped at all.
  // Retired experiences and those from `below_id` on do not count.
  bool mapped_near(const Pose2& pose, double radius, double heading, int below_id) const;
  // The one neighbourhood query (mapped_near, the localiser's search around a candidate): calls
  // f(id, distance_m) for every experience within `radius` of `pose` and turned at most `heading`
  // from it, in id order, neither retired nor from `below_id` on; f returns false to stop.
  template <class F>
  void for_each_near(const Pose2& pose, double radius, double heading, int below_id, F&& f) const {
    const double r2 = radius * radius;
    const double c = std::cos(pose.theta), s = std::sin(pose.theta), min_cos = std::cos(heading);
    const size_t n = std::min(x_.size(), static_cast<size_t>(std::max(below_id, 0)));
    for (size_t i = 0; i < n; ++i) {
      const double dx = x_[i] - pose.x, dy = y_[i] - pose.y;
      const double d2 = dx * dx + dy * dy;
      if (d2 <= r2 && c_[i] * c + s_[i] * s >= min_cos && !meta_[i].retired) {
        if (!f(static_cast<int>(i), std::sqrt(d2))) return;
      }
    }
  }
  // Retires experiences [from_id, to_id) (Experience::retired).
  void retire(int from_id, int to_id);
  // The experiences of a template that are not retired (empty if it has none).
  const std::vector<int>& experiences_of(int template_id) const;
  void relax(int loops);
  // Frozen: on_cycle never creates experiences or links; a matched template moves the current
  // experience to its nearest (in pose cells) experience within the gate's budget, whatever the
  // view shift.
  void set_frozen(bool frozen) { frozen_ = frozen; }

  const ExperienceMapParams& params() const { return params_; }
  // New parameters; every link's σ² and whether it is robust follow them.
  void set_params(const ExperienceMapParams& p);

  void serialise(std::vector<uint8_t>& out) const;
  // format_version: the checkpoint's; version 1 had no view shifts (read as 0); before version 6 links
  // had no recognised ends (a link made after its `to` experience is read as a re-localisation's, one
  // end recognised) and the link scales restart at 1. Template ids must be
  // below num_templates, poses finite and headings unit vectors (std::runtime_error otherwise).
  void deserialise(const std::vector<uint8_t>& in, size_t& pos, uint32_t format_version, int num_templates);

 private:
  void sync_poses() const;
  double link_sigma2(const Pose2& delta, int recognised_ends) const;

  ExperienceMapParams params_;
  mutable std::vector<Experience> meta_;
  mutable bool poses_dirty_ = false;
  std::vector<Link> links_;
  std::vector<std::vector<int>> by_template_;
  // Relaxation state, structure of arrays.
  std::vector<double> x_, y_, c_, s_;
  std::vector<int32_t> lfrom_, lto_;
  std::vector<double> ldx_, ldy_, ldc_, lds_;
  std::vector<double> lw_;       // 1 / σ² of every link
  std::vector<uint8_t> lrobust_;  // whether it is scaled by DCS
  std::vector<double> lscale_;   // its scale s² after the last relaxation
  std::vector<double> lgate2_;   // its gate², m² (Link::gate_m)
  std::vector<double> inv_;      // scratch: 1 / (a node's weight sum) in the current loop
  std::vector<double> ax_, ay_, as_, aw_;  // scratch: per-loop weighted sums of errors, and of weights
  int current_ = -1;
  bool current_recognised_ = false;  // the robot re-localised onto the current experience (not made it)
  Pose2 offset_;
  double travel_ = 0.0;  // m since the last re-localisation
  bool frozen_ = false;
};

}  // namespace whiskeye::slam
