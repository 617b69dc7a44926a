// Global localisation in the experience map (docs/slam-core.md, "Global localisation"): where
// odometry cannot say where the robot is — a restart on a saved map, a kidnap — the pose is held as
// unknown (LOCALISING) while competing hypotheses are weighed over a sequence of cycles, and the
// map is rejoined only when one of them is clearly ahead.
//
// A hypothesis is a candidate pose of the base in the map frame, carried as a correction C of the
// dead-reckoned pose (hypothesis = C ∘ map.current_pose()): while localising the map's current
// experience stays put and its offset integrates the odometry, so every hypothesis moves with the
// odometry without integrating it again. Each cycle that recognises a template is evidence: a
// hypothesis with an experience within `radius` (and `heading` of its own heading) of that
// template, or of any template the view would be recognised as too, is supported (+1, and
// re-anchored on that experience, which removes its drift); one where the map has experiences but
// none the view is recognised as loses 1 (the place is known and looks otherwise) — unless vision
// alone would recognise one there and only touch objects (Recognition::SeenOnly: touch withholds
// support, it does not contradict); one in a place never mapped keeps its score. Every experience of the template that supports no hypothesis starts one. The
// best commits when its score reaches `commit_score` and leads every hypothesis elsewhere by
// `commit_margin`. Pure: no I/O, time passed in.
//
// While tracking, kidnap detection: a recognised template whose every experience lies beyond the
// odometry-consistency gate's budget is a disagreement between what the robot sees and where it
// thinks it is — if the map knows the place it thinks it is at (in a place never mapped, a view
// like one elsewhere is aliasing). `kidnap_disagreements` of them among the last `kidnap_window`
// recognitions (a look-alike within the budget, accepted now and then, does not hide the rest)
// start localising with the tracked pose as one of the hypotheses, ahead by commit_margin
// (odometry was trusted until then; a false alarm ends by committing back to it).
#pragma once

#include "whiskeye/common/params.h"
#include "whiskeye/common/se2.h"
#include "whiskeye/slam/types.h"

#include <cstdint>
#include <deque>
#include <functional>
#include <limits>
#include <optional>
#include <vector>

namespace whiskeye::slam {

class ExperienceMap;

struct LocaliserParams {
  // Gate-refused recognitions among the last kidnap_window recognitions (where the map knows the
  // place) that start localising; 0: never.
  int kidnap_disagreements = 0;
  int kidnap_window = 8;
  double radius = 0.3;           // m: an experience this near a hypothesis supports it
  double heading = 0.5;          // rad: ... and turned at most this much from it
  int commit_score = 3;          // supports minus misses the best needs
  int commit_margin = 2;         // ... and its lead over the best hypothesis farther than `radius`
  int max_hypotheses = 200;      // the best kept when more are started
  int drop_score = -3;           // a hypothesis at or below this is dropped
  // m travelled while localising after which the prior (the tracked pose, when there is one) is
  // taken back if no place won: a robot that is not where the map has been keeps mapping.
  double give_up_m = 6.0;
  // s: a daemon resuming a checkpoint localises first when the odometry resumes more than this
  // after the checkpoint's last sample (the robot may have been moved while slamd was down: a power
  // cycle, a new battery); a quick restart goes on tracking (a move in it is a kidnap, detected as
  // any). 0: always localise on resume.
  double resume_gap_s = 30.0;
};
void load(const ParamNode& node, LocaliserParams& p);

enum class LocalisationState : uint8_t { Tracking = 0, Localising = 1 };

// A localisation's outcome: the base is at `offset` from `experience` (both in the map frame).
struct Commit {
  int experience = -1;
  Pose2 offset;
  bool gave_up = false;  // the prior taken back after give_up_m, not a place recognised
  // Experiences [retire_from, retire_to) were made while the robot was lost (the disagreements
  // before a kidnap was detected): the caller retires them (ExperienceMap::retire). Empty when the
  // tracked pose won (a false alarm: they were made where the robot was).
  int retire_from = 0;
  int retire_to = 0;
};

class Localiser {
 public:
  explicit Localiser(const LocaliserParams& params = {});

  LocalisationState state() const { return state_; }
  bool localising() const { return state_ == LocalisationState::Localising; }
  int hypotheses() const { return static_cast<int>(hyps_.size()); }
  int64_t kidnaps_detected() const { return kidnaps_detected_; }
  int64_t localisations() const { return localisations_; }
  const LocaliserParams& params() const { return params_; }

  // Starts localising. with_prior: the map's current pose is one hypothesis (a resumed checkpoint,
  // a suspected kidnap), with `prior_score`; without, every place is open (a saved map).
  // Experiences from `evidence_below` on are no evidence (made where the robot only thought it was).
  void start(bool with_prior, int prior_score = 0, int evidence_below = std::numeric_limits<int>::max());
  // Whether the map may go on growing while localising: with where odometry says as a candidate,
  // tentatively (what is made meanwhile is no evidence, and is retired if another place wins).
  bool learning() const { return localising() && has_prior(); }
  bool has_prior() const;

  // While tracking: the outcome of one recognition by the map's action rule (accepted: the gate let
  // the template's experience be joined or stayed on; refused: every experience of the template lay
  // beyond the budget). first_new_id: the experience this cycle made (map.size() if none). Returns
  // true when this starts localising (a suspected kidnap); the caller then passes the same
  // recognition to on_localising_cycle as the first evidence. Experiences made since the first
  // disagreement are no evidence for any place (they were put where the robot thought it was).
  bool on_tracking_recognition(bool refused, int recognised_template, int first_new_id, const ExperienceMap& map);

  // While localising: one cycle. template_id: the template recognised this cycle, or -1.
  // travelled_m: distance travelled by odometry since the previous cycle. recognises(t): how the
  // cycle's view relates to template t (TemplateStore::Recogniser; empty: only template_id counts).
  // Returns the commit that ends localising, if this cycle brings one.
  std::optional<Commit> on_localising_cycle(int template_id, double travelled_m, const ExperienceMap& map,
                                            const std::function<Recognition(int)>& recognises = {});

  void serialise(std::vector<uint8_t>& out) const;
  void deserialise(const std::vector<uint8_t>& in, size_t& pos, int num_experiences);

 private:
  struct Hypothesis {
    Pose2 correction;  // hypothesis = correction ∘ dead-reckoned pose
    int anchor = -1;   // the experience that last supported it (-1: none yet, the prior)
    int score = 0;
    bool prior = false;
  };
  Pose2 pose_of(const Hypothesis& h, const Pose2& dead_reckoned) const { return compose(h.correction, dead_reckoned); }
  std::optional<Commit> commit_if_ahead(const ExperienceMap& map);
  Commit commit(const Hypothesis& h, const ExperienceMap& map, bool gave_up);

  LocaliserParams params_;
  LocalisationState state_ = LocalisationState::Tracking;
  std::vector<Hypothesis> hyps_;
  // The last kidnap_window recognitions while tracking: refused or not, and the first experience
  // made at or after each.
  struct TrackedRecognition {
    bool refused = false;
    int first_new_id = 0;
  };
  std::deque<TrackedRecognition> recent_;
  int evidence_below_ = std::numeric_limits<int>::max();  // experiences from this id on are no evidence
  double localising_m_ = 0.0;  // travelled since localising started
  int64_t kidnaps_detected_ = 0;
  int64_t localisations_ = 0;
};

}  // namespace whiskeye::slam
