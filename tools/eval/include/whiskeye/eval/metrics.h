// The evaluation metrics — ATE, the accuracy figure, and the paper's Table I (LEM, ExM, EnM) — as
// pure functions, following the contract in ../shared/design/metrics.md. Plain structs in, plain
// structs out: no LCM, no files, no clocks — `vita-eval` reads the log and converts; tests build the
// inputs by hand.
//
// Frames: ground truth is the pose of the robot base in the world frame; pose estimates and
// experiences are poses of the base in the SLAM map frame. T_world_map ties them together.
// Relative poses use common/se2.h: a ⊖ b := between(a, b) = "b expressed in a's frame".
#pragma once

#include "whiskeye/common/se2.h"

#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <unordered_map>
#include <vector>

namespace whiskeye::eval {

struct PoseSample {
  int64_t utime = 0;
  Pose2 pose;
};

enum class EventType { kSameExperience, kNewExperience, kRelocalise };

// VITA_POSE's localisation state at a time.
struct StateSample {
  int64_t utime = 0;
  bool localising = false;
};

struct ExperienceEvent {
  int64_t utime = 0;
  int64_t cycle = 0;
  EventType type = EventType::kSameExperience;
  int32_t from_id = -1;
  int32_t to_id = -1;
  bool localising = false;  // VITA_EVENT.localisation after the cycle: LOCALISING (to_id is then no claim)
};

struct MapExperience {
  int32_t id = -1;
  Pose2 pose;  // map frame, after relaxation
  int64_t utime_created = 0;
  bool dense = false;
};

struct MapLink {
  int32_t from_id = -1;
  int32_t to_id = -1;
  bool revoked = false;  // the back end turned it off (VITA_MAP link_t.revoked)
  Pose2 delta;           // what it claims: `to` in `from`'s frame
};

struct ExperienceMap {
  std::vector<MapExperience> experiences;
  std::vector<MapLink> links;
  std::size_t revoked_links() const;
  const MapExperience* find(int32_t id) const;  // linear: a loop looks up through an ExperienceIndex
};

// The map's experiences by id in constant time, answering as ExperienceMap::find (the first of equal
// ids); valid while the map is unchanged.
class ExperienceIndex {
 public:
  explicit ExperienceIndex(const ExperienceMap& map);
  const MapExperience* find(int32_t id) const;

 private:
  std::unordered_map<int32_t, const MapExperience*> by_id_;
};

// Ground truth, interpolated between samples: positions linearly, headings along the shorter arc.
// Queries outside [begin, end] return nothing: the metrics exclude (and count) such times rather
// than extrapolate. Never interpolated across a jump (a kidnap: the truth moves metres between two
// samples): a time before the jump gets the sample before it, a time at or after it the sample after
// it. Two sessions' truth merged (a map made in an earlier session) has none between the sessions.
class GroundTruth {
 public:
  // Sorts by time; of samples with equal times the last one wins. `jumps`: the kidnaps' utimes.
  explicit GroundTruth(std::vector<PoseSample> samples, std::vector<int64_t> jumps = {});
  // This session's truth and an earlier session's (whose time range must not overlap it), with
  // nothing in between.
  GroundTruth(const std::vector<PoseSample>& samples, const std::vector<PoseSample>& earlier_session,
              std::vector<int64_t> jumps);
  std::optional<Pose2> at(int64_t utime) const;
  // True when the truth jumps (or the sessions change) in (from, to]: no path runs from one to the other.
  bool breaks_between(int64_t from, int64_t to) const;
  bool empty() const { return samples_.empty(); }
  int64_t begin_utime() const { return samples_.empty() ? 0 : samples_.front().utime; }
  int64_t end_utime() const { return samples_.empty() ? 0 : samples_.back().utime; }
  const std::vector<PoseSample>& samples() const { return samples_; }

  // Distance travelled (m) in [from, to], along the samples and never across a jump.
  double path_length(int64_t from, int64_t to) const;

 private:
  std::vector<PoseSample> samples_;
  std::vector<int64_t> jumps_;        // sorted
  std::vector<int64_t> hole_after_;   // sample times after which there is no truth until the next sample
};

// The paper's correct re-localisation (metrics.md): the robot now within this of where the target
// experience was created. The one definition; vita-eval's defaults and docs take it from here.
inline constexpr double kPaperCorrectPosition_m = 0.08;
inline constexpr double kPaperCorrectAngle_deg = 4.6;
// A false closure (metrics.md): the target created further than this from the robot now (either
// bound). Wider than the paper's, so that the neighbour a whisk cycle away (experiences are 7-15 cm
// apart) is a neighbour miss, not an aliasing failure.
inline constexpr double kFalseClosurePosition_m = 0.25;
inline constexpr double kFalseClosureAngle_deg = 15.0;

// ATE per window of this many laps by default: the long-run targets compare the first and the last four.
inline constexpr double kAteWindowLaps = 4.0;

struct EvalParams {
  double correct_position_m = kPaperCorrectPosition_m;              // ExM: correct within this (m) ...
  double correct_angle_rad = deg_to_rad(kPaperCorrectAngle_deg);    // ... and this heading difference
  double false_closure_position_m = kFalseClosurePosition_m;        // false closure beyond this (m) ...
  double false_closure_angle_rad = deg_to_rad(kFalseClosureAngle_deg);  // ... or this heading difference
  double ate_window_laps = kAteWindowLaps;       // ATE per window of this many laps
  double centre_x = 0.0;                         // arena centre for the first revolution (m)
  double centre_y = 0.0;
  std::optional<double> base_duration_s;         // if set, base set = first S seconds of GT instead
  // The log is a session on a saved map: its start is a localisation instant (also detected when the
  // map has experiences created before the log's first ground truth).
  bool session_start = false;
};

// ---- Alignment ----

struct Alignment {
  bool valid = false;
  std::string reason;   // why not valid
  Pose2 T_world_map;    // world pose of the map frame
};

// The contract's alignment: the single transform putting the first experience (earliest
// utime_created; ties by smaller id) onto the ground-truth pose at its creation time.
Alignment align_by_first_experience(const ExperienceMap& map, const GroundTruth& gt);

// The least-squares rigid SE(2) transform (no scale) putting the estimated positions onto ground
// truth at their times (closed form: Horn 1987 / Umeyama 1991 in 2-D). ATE's alignment.
Alignment align_best_fit(const std::vector<PoseSample>& estimate, const GroundTruth& gt);

// ---- LEM ----

struct ErrorStats {
  double rmse = 0.0;
  double mean_abs = 0.0;
  double std_abs = 0.0;  // population standard deviation of |e|
};

struct LemResult {
  std::size_t samples_used = 0;
  std::size_t samples_outside_gt = 0;  // excluded: no ground truth at their time
  ErrorStats position_m;
  ErrorStats orientation_rad;
};

LemResult compute_lem(const std::vector<PoseSample>& estimate, const GroundTruth& gt,
                      const Pose2& T_world_map);

// ---- ATE: the absolute trajectory error, the accuracy figure every target uses ----
//
// metrics.md: every VITA_POSE sample with ground truth at its time, except those reported while
// LOCALISING (they claim nothing: excluded and counted), aligned by the one best-fit SE(2)
// transform of those samples (align_best_fit); the position error after it. Over long runs also per
// window of `ate_window_laps` laps of ground-truth travel (lap_length()), each under the run's
// alignment and under the window's own best fit (the two agree when the map is only offset per
// window, and differ when its shape is wrong within the window).

struct AteStats {
  double rmse = 0.0;
  double mean = 0.0;
  double median = 0.0;  // of the position errors (the mean of the middle two of an even count)
  double max = 0.0;
};

struct AteWindow {
  double from_lap = 0.0;   // laps of ground-truth travel from the first sample used ...
  double to_lap = 0.0;     // ... to the last sample in the window (the last window may be short)
  int64_t begin_utime = 0;
  int64_t end_utime = 0;
  std::size_t samples = 0;
  double rmse = 0.0;                  // under the whole run's alignment
  std::optional<double> rmse_own_fit; // under the window's own best fit (none if it cannot be fitted)
};

struct AteResult {
  std::size_t samples_used = 0;
  std::size_t samples_outside_gt = 0;  // excluded: no ground truth at their time
  std::size_t samples_localising = 0;  // excluded: reported while LOCALISING
  Alignment alignment;                 // the best fit of the samples used
  std::optional<AteStats> position_m;  // none without a valid alignment
  std::optional<double> lap_length_m;
  double window_laps = 0.0;
  std::vector<AteWindow> windows;      // empty without a lap length
};

// The pose samples that claim a pose: those not reported while LOCALISING. `states` is VITA_POSE's
// localisation state of each `estimate` sample (parallel to it), or empty when none was reported;
// throws std::invalid_argument when it is neither (and there are poses).
std::vector<PoseSample> claimed_poses(const std::vector<PoseSample>& estimate, const std::vector<StateSample>& states);

// Over claimed_poses(estimate, states) (throws as it does).
AteResult compute_ate(const std::vector<PoseSample>& estimate, const std::vector<StateSample>& states,
                      const GroundTruth& gt, double window_laps = kAteWindowLaps);

// ---- ExM ----

// A judged re-localisation: correct by the paper's thresholds; else a neighbour miss (within the
// false-closure tolerance) or a false closure (beyond it).
enum class Closure { kCorrect, kNeighbourMiss, kFalse };

// "correct", "neighbour" or "false" (the trace's and the JSON's spelling).
const char* closure_name(Closure c);

// The verdict on a re-localisation that leaves the robot `position_error_m` and `angle_error_rad`
// (|wrapped|) from where its target was created. Bounds are inclusive: at exactly the paper's
// threshold it is correct, at exactly the false-closure tolerance a neighbour miss.
Closure classify_closure(double position_error_m, double angle_error_rad, const EvalParams& params);

struct Relocalisation {
  int64_t utime = 0;
  int32_t from_id = -1;
  int32_t to_id = -1;
  Pose2 gt_now;             // ground truth at the event
  Pose2 gt_target_created;  // ground truth at the target experience's creation
  double position_error_m = 0.0;
  double angle_error_rad = 0.0;  // |wrapped heading difference|
  bool correct = false;          // closure == Closure::kCorrect
  Closure closure = Closure::kFalse;
  bool after_base_set = false;
};

struct ExmResult {
  bool base_end_found = false;     // false: the revolution was never completed (everything is base)
  int64_t base_end_utime = 0;      // events strictly after this time are "after the base set"
  double base_end_s = 0.0;         // the same, in seconds after the first ground-truth sample
  std::size_t base_set_size = 0;   // experiences created at or before base_end_utime
  std::size_t experience_events_after_base = 0;  // new experiences + re-localisations
  std::size_t relocalisations_after_base = 0;
  std::size_t correct_after_base = 0;
  std::size_t relocalisations_total = 0;         // including those during the base set
  std::size_t correct_total = 0;
  std::optional<double> arr;   // undefined when there is no experience event after the base set
  // metrics.md: correct / re-localisations, all of them (the base set's too: a false loop closure in
  // the first lap counts). Undefined, not 1, when there is none.
  std::optional<double> arcr;
  std::optional<double> arcr_after_base;  // the same over ARR's re-localisations only (not the metric)
  // Paper-wrong re-localisations (all of them, as ARCR's) split by the false-closure tolerance.
  std::size_t false_closures = 0;
  std::size_t neighbour_misses = 0;
  std::optional<double> false_closure_worst_m;  // the largest position error of a false closure; none without one
  std::optional<double> neighbour_miss_share;   // neighbour misses / paper-wrong; undefined without a wrong one
  // How far apart the run makes experiences: for every NEW_EXPERIENCE after the first, the step from
  // the experience current before it to the new one, by ground truth at their creation times. Half a
  // step beyond the paper's thresholds makes neighbour misses unavoidable.
  std::size_t spacing_steps = 0;
  std::optional<double> spacing_median_m;
  std::optional<double> spacing_median_heading_rad;  // median |wrapped heading difference|
  std::size_t experiences_created = 0;  // NEW_EXPERIENCE events (with ground truth)
  std::size_t valid_experiences = 0;
  std::optional<double> valid_fraction;
  // Events not counted: no ground truth at the event or at the target's creation, unknown target,
  // or a RELOCALISE that does not change the current experience.
  std::size_t events_outside_gt = 0;
  std::size_t relocalise_unknown_target = 0;
  std::size_t relocalise_to_current = 0;
  std::vector<Relocalisation> relocalisations;  // all counted ones, in time order
};

// Time at which ground truth has completed its first full revolution (2π of net polar-angle travel
// around the centre), or the configured base duration after the first GT sample.
std::optional<int64_t> base_set_end(const GroundTruth& gt, const EvalParams& params);

// `events` in any order (sorted by utime, then cycle, internally). An experience's creation time is
// its utime_created in the final map (as for EnM), else the time of the NEW_EXPERIENCE event that
// created it (an experience dropped from the map).
ExmResult compute_exm(const std::vector<ExperienceEvent>& events, const ExperienceMap& map,
                      const GroundTruth& gt, const EvalParams& params);

// ---- EnM ----

struct EnmResult {
  std::size_t links_used = 0;
  std::size_t links_excluded = 0;  // endpoint missing from the map, or no GT at a creation time
  std::optional<double> enm;            // (1/N) Σ trans² + rot²; undefined with N = 0
  std::optional<double> translation;    // (1/N) Σ trans²  (m²)
  std::optional<double> rotation;       // (1/N) Σ rot²    (rad²)
};

// For every link (i = from, j = to): δ̂ = x̂_i ⊖ x̂_j, δ = x_i ⊖ x_j, error = δ̂ ⊖ δ.
EnmResult compute_enm(const ExperienceMap& map, const GroundTruth& gt);

// ---- Localisation: after a kidnap, or in a session on a saved map ----
//
// An instant T at which the robot does not know where it is and odometry cannot tell it: every
// kidnap (SIM_FAULT), and the start of a session on a saved map. Until the next instant (or the
// log's end), every VITA_EVENT that claims a place is judged alignment-free as a re-localisation is
// (the truth now against the truth where its target was created, classify_closure()): a RELOCALISE,
// or a SAME_EXPERIENCE, but not a NEW_EXPERIENCE (made where the robot is, it claims nothing), not
// an event that reports LOCALISING (it says it does not know), and not staying on the experience
// current at T (the place before the kidnap: not a closure, the robot just has not noticed yet).
//   - the first correct localisation: the first judged event whose target was created before T and
//     is correct by the paper's tolerance, after which no judged event up to the window's end is a
//     false closure (the pose then stays within the false-closure tolerance); its time and the
//     distance travelled (ground truth) from T, and that distance in laps;
//   - false localisations: false closures among the judged events before it (all of the window's if
//     it never comes); consecutive events on the same target count once;
//   - time reporting LOCALISING in the window (VITA_POSE.localisation held until the next sample,
//     else VITA_EVENT's);
//   - LEM after localisation: the mean position (and heading) error of the judged events from the
//     localisation to the window's end.

struct LocalisationInstant {
  enum class Kind { kKidnap, kSessionStart };
  Kind kind = Kind::kKidnap;
  int64_t utime = 0;
};

// "kidnap" or "session_start" (the JSON's and the trace's spelling).
const char* instant_name(LocalisationInstant::Kind kind);

struct Localisation {
  LocalisationInstant instant;
  int64_t window_end_utime = 0;          // the next instant, or the log's end
  std::optional<Pose2> gt_at;            // the truth at the instant (where the robot was put down)
  bool localised = false;
  int64_t localised_utime = 0;
  ExperienceEvent localised_by;          // the event of the first correct localisation
  Pose2 gt_localised;                    // the truth then ...
  Pose2 gt_target_created;               // ... and where its target was created
  double position_error_m = 0.0;
  double angle_error_rad = 0.0;
  std::optional<double> time_s;          // from the instant to the first correct localisation
  std::optional<double> distance_m;      // travelled meanwhile (ground truth)
  std::optional<double> laps;            // distance_m / the lap length
  std::size_t false_localisations = 0;
  std::vector<Relocalisation> false_events;  // each false localisation counted
  std::size_t judged_events = 0;
  std::size_t unjudged_events = 0;       // claims without ground truth or with an unknown target
  double localising_s = 0.0;
  std::size_t lem_events = 0;
  std::optional<double> lem_after_m;     // mean position error from the localisation on
  std::optional<double> lem_after_angle_rad;
};

struct LocalisationReport {
  std::vector<Localisation> instants;
  std::optional<double> lap_length_m;    // lap_length() of this run's ground truth
  std::size_t localised = 0;
  std::size_t within_one_lap = 0;
  std::size_t within_two_laps = 0;
  std::optional<double> worst_laps;      // undefined when one was never localised (or no lap length)
  std::size_t false_localisations = 0;
  std::size_t false_localisations_max = 0;  // at one instant
  std::size_t with_false_localisation = 0;  // instants with at least one
  double localising_s = 0.0;
  std::size_t lem_events = 0;
  std::optional<double> lem_after_m;     // over every instant's events after its localisation
};

// The length of one lap of the trajectory: the distance travelled per 2π of heading change, by ground
// truth (the robot circles facing outwards or inwards, so its heading turns once a lap), never across
// a jump. Undefined when the heading turns less than half a turn in all.
std::optional<double> lap_length(const GroundTruth& gt);

// `truth` judges the targets (it includes the session that made a saved map); `own` is this log's
// ground truth (distances, the log's end).
LocalisationReport compute_localisation(const std::vector<ExperienceEvent>& events, const ExperienceMap& map,
                                        const GroundTruth& truth, const GroundTruth& own,
                                        std::vector<LocalisationInstant> instants,
                                        const std::vector<StateSample>& states, const EvalParams& params);

// ---- Everything ----

// One cycle's template-matching result (VITA_MATCH); only the per-cycle trace uses it.
struct TemplateMatch {
  int64_t utime = 0;
  int64_t cycle = 0;
  int32_t template_id = -1;
  bool is_new = false;
  double error = 0.0, visual_error = 0.0, pfh_error = 0.0, sda_error = 0.0;  // divided by their σ
  int32_t visual_shift = 0;
  bool visual_used = false;
  bool tactile_used = false;
};

// A simulated sensor fault beginning or ending (SIM_FAULT), named for attribution: "board_offline 2",
// "camera_blackout", "odometry_slip x1.2", ...; only the per-cycle trace and the report use it.
struct FaultEvent {
  int64_t utime = 0;
  std::string name;
  bool active = true;  // begins (true) or ends (false)
};

struct EvalInput {
  std::vector<PoseSample> estimate;       // VITA_POSE
  std::vector<StateSample> states;        // VITA_POSE.localisation
  std::vector<ExperienceEvent> events;    // VITA_EVENT
  ExperienceMap map;                      // last VITA_MAP
  std::vector<PoseSample> ground_truth;   // GROUND_TRUTH
  std::vector<TemplateMatch> matches;     // VITA_MATCH
  std::vector<FaultEvent> faults;         // SIM_FAULT, in log order (kidnaps apart)
  std::vector<PoseSample> kidnaps;        // SIM_FAULT KIND_KIDNAP: when, and the true pose put down at
  // GROUND_TRUTH of the session that made a saved map (vita-eval --map-truth): the map's experiences
  // created then are judged by it.
  std::vector<PoseSample> map_ground_truth;
};

// The ground truth every judgement uses: the log's, with its kidnaps as jumps, and the map's session's
// before it.
GroundTruth truth_of(const EvalInput& input);

// The localisation instants of a run: its kidnaps, and its start when `params.session_start` or when
// its map has an experience created before its first ground truth.
std::vector<LocalisationInstant> localisation_instants(const EvalInput& input, const EvalParams& params);

// The final map's links against the truth, alignment-free: a link claims that `to` was made at
// `from` ∘ delta, and where the robot was when each end was made says whether it was (the ends' first
// ground truth). Wrong: off by more than the false-closure tolerance, either bound (a false closure's
// link, odometry across an undetected kidnap, a wrong closure injected on purpose). The back end is
// right when it keeps the right links and revokes the wrong ones.
struct LinkJudgement {
  std::size_t judged = 0;          // links with truth at both ends' creation
  std::size_t wrong = 0;
  std::size_t wrong_kept = 0;      // wrong and not revoked: the map is bent by them
  std::size_t right_revoked = 0;   // right but revoked: a constraint lost
  std::optional<double> worst_kept_m;  // the largest position error of a link kept
};
LinkJudgement judge_links(const ExperienceMap& map, const GroundTruth& gt, const EvalParams& params);

struct EvalResult {
  // False for a log without GROUND_TRUTH (a real robot's run): then nothing that needs truth is
  // computed — no alignment, LEM, EnM, correctness (ARCR, valid fraction) — and ExM only counts
  // events; ARR too with `base_duration_s` (the base set then starts at the first pose or event).
  bool ground_truth = true;
  Alignment alignment;                    // the paper's: the first experience onto ground truth
  std::optional<LemResult> lem;           // the paper's LEM, with that alignment
  AteResult ate;                          // the accuracy figure (best-fit alignment)
  ExmResult exm;
  EnmResult enm;
  LinkJudgement links;
  std::optional<LocalisationReport> localisation;  // when the run has a localisation instant
};

EvalResult evaluate(const EvalInput& input, const EvalParams& params);

// ExM without ground truth: the experience events counted (new experiences, re-localisations, none
// judged), and ARR when `params.base_duration_s` sets the base set (from `start_utime`); every
// correctness field stays 0 and ARCR and the valid fraction undefined.
ExmResult count_exm_without_truth(const std::vector<ExperienceEvent>& events, const ExperienceMap& map,
                                  const EvalParams& params, int64_t start_utime);

// When a run starts: its first ground-truth sample, else its first pose estimate or event (0 if none).
int64_t run_start_utime(const EvalInput& input);

// ---- Per-cycle trace ----

// What happened in one whisk cycle, against ground truth: where a run went wrong, and why. One row
// per VITA_EVENT, in the order compute_exm() takes them.
struct CycleTrace {
  ExperienceEvent event;
  double t_s = 0.0;                              // seconds after run_start_utime()
  std::optional<Pose2> gt;                       // ground truth at the event (none outside it)
  std::optional<Relocalisation> relocalisation;  // a counted re-localisation: its error, correctness
  std::optional<TemplateMatch> match;            // the cycle's VITA_MATCH (the same cycle number)
  std::vector<std::string> active_faults;        // simulated faults active at the event (SIM_FAULT)
  // The localisation metric's marks: "kidnap" / "session_start" on the first event after an
  // instant, "localised" on its first correct localisation, "false_localisation" on a counted one.
  std::vector<std::string> localisation_marks;
};

// `exm` is compute_exm()'s result for the same input (its re-localisations are joined by time and
// target); `localisation`, if given, compute_localisation()'s.
std::vector<CycleTrace> trace_cycles(const EvalInput& input, const ExmResult& exm,
                                     const LocalisationReport* localisation = nullptr);

}  // namespace whiskeye::eval
