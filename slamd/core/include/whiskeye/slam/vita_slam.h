// ViTa-SLAM (paper Algorithm 1): one call per whisk cycle with the camera frame, the whisk cycle and
// the odometry since the previous cycle. Per cycle:
//   1. path integration: every odometry sample moves the experience map's offset, and the pose
//      cells take one step per path_integration_period with the samples' mean (body-frame vx, vy, ω);
//   2. templates: visual (if the mode uses vision and a frame came) and tactile (if the mode uses
//      touch and a whisk cycle came). ViTa with both fuses them (MatchParams::tactile_veto: touch
//      adds evidence where both cycles touched something, and otherwise only vetoes what vision
//      accepts). ViTa with one sense missing is degraded: the other may recognise a known template,
//      but no template, pose-cell energy or experience comes of it (a missing sense never counts
//      as a match); the single-sense modes need their one sense;
//   3. match against every stored template: ε ≤ τ → match (inject energy at the template's pose
//      cells, with the decay rule) else a new template (stored with the current pose-cell estimate);
//   4. the experience map's action rule (same / new / re-localise) and relaxation — or, while
//      LOCALISING (a restart on a saved map, a suspected kidnap: localiser.h), the recognition is
//      evidence for the competing places and the map is left as it is until one wins.
// State (templates, pose cells, map, odometry clock) serialises to a versioned binary blob and
// restores exactly: a restored instance produces byte-identical results.
//
// Checkpoint format (all little-endian):
//   magic "VITASLAM" (8 bytes) | u32 version (7; 1 to 6 are still read) | u8 mode | i64 last odometry utime | u8 has it |
//   5 × i64 stats | template store | pose cells | experience map | localiser (version ≥ 4) | u32 FNV-1a of all previous bytes
//   template store: i32 w, i32 h, then arrays (u64 count + elements): visual u8, visual mean f32,
//     has_visual u8, pfh u16, sda f32, has_tactile u8, num_contacts i32, pc (x,y,θ) f64, decay f64,
//     sensed whiskers u32 (bit w: whisker w had data; version ≥ 5, before: all)
//   pose cells: i32 dim_xy, i32 dim_theta, u64 count + f32 activity [θ][y][x]
//   experience map: u64 n, n × (f64 x, y, cos θ, sin θ, pc_x, pc_y, pc_θ, i64 utime, i32 template,
//     visual, tactile id, u8 dense, i32 view shift (version ≥ 2), u8 retired (version ≥ 4)) | u64 links, each (i32 from, to, f64 dx, dy, dθ, i64 utime,
//     u8 recognised ends, f64 scale (version ≥ 6), f64 gate m (version ≥ 7, may be +inf)) |
//     i32 current | u8 current recognised (version ≥ 6) | f64 offset x, y, θ | f64 distance travelled since the last re-localisation (version ≥ 3)
//   localiser: u8 state | u32 n, n × (u8 refused, i32 first experience made since) of the last recognitions |
//     i32 first experience not evidence | f64 m localising | i64 kidnaps detected | i64 localisations |
//     u64 n, n × (f64 correction x, y, θ, i32 anchor, i32 score, u8 prior)
#pragma once

#include "whiskeye/common/params.h"
#include "whiskeye/common/robot_geometry.h"
#include "whiskeye/slam/experience_map.h"
#include "whiskeye/slam/localiser.h"
#include "whiskeye/slam/pose_cells.h"
#include "whiskeye/slam/tactile_template.h"
#include "whiskeye/slam/template_store.h"
#include "whiskeye/slam/types.h"
#include "whiskeye/slam/visual_template.h"
#include "whiskeye/slam/wrong_closures.h"

#include <cstdint>
#include <optional>
#include <span>
#include <vector>

namespace whiskeye::slam {

struct SlamParams {
  Mode mode = Mode::Vita;
  VisualParams visual;
  TactileParams tactile;
  MatchParams match;
  PoseCellParams pose_cells;
  ExperienceMapParams experience_map;
  LocaliserParams localisation;
  double max_odometry_dt = 1.0;  // s; a longer gap between odometry samples is integrated as this
  // s; odometry is summed over this long before one pose-cell step (attractor dynamics + shift).
  // The cells' dynamics need not run at the base's 50 Hz: the packet moves under a cell per step
  // at walking speed either way, and the step is the costliest part of a cycle. 0 = every sample.
  double path_integration_period = 0.1;
};
// `node` is the `slam:` section of config/slam.yaml. Strict: unknown keys and out-of-range values
// are ParamErrors naming the key.
void load(const ParamNode& node, SlamParams& p);


struct SlamStats {
  int64_t cycles = 0;
  int64_t bad_images = 0;           // frames refused (InputError); the cycle went on without vision
  int64_t empty_whisk_cycles = 0;   // whisk cycles without a valid sample; went on without touch
  int64_t odometry_rejected = 0;    // samples out of order, non-finite or faster than kMaxOdometrySpeed: skipped
  int64_t odometry_gaps = 0;        // dt > max_odometry_dt, clamped; or time back by more (a clock step)
};

class VitaSlam {
 public:
  // The checkpoint format written (the version above); older ones down to 1 are read.
  // 2: experiences carry their view shift; 3: the map its travelled distance; 4: the localiser's
  // state; 5: each template the whiskers it sensed; 6: each link its recognised ends and scale, the
  // map whether the robot recognised its current experience; 7: each link its gate.
  static constexpr uint32_t kCheckpointFormat = 7;

  VitaSlam(const SlamParams& params, const RobotGeometry& geometry);

  CycleResult process_cycle(const CycleInput& input);

  const ExperienceMap& map() const { return map_; }
  const TemplateStore& templates() const { return store_; }
  const PoseCells& pose_cells() const { return cells_; }
  const SlamParams& params() const { return params_; }
  const SlamStats& stats() const { return stats_; }
  // Current experience ∘ its odometry offset ∘ the odometry since the last cycle.
  Pose2 dead_reckon(const Pose2& odometry_offset_since_last_cycle) const;

  // Localise in the existing map without growing it (a saved map reused across runs): no new
  // templates, experiences or links; a matched template re-localises to its nearest experience.
  void set_localise_only(bool on) {
    localise_only_ = on;
    map_.set_frozen(on);
  }
  bool localise_only() const { return localise_only_; }

  // Holds the pose as unknown until a place wins (localiser.h): after loading a saved map
  // (with_prior false: the robot may be anywhere) or resuming a checkpoint (true: where it was
  // left is one of the candidates, with no head start). Nothing to do on an empty map.
  void start_localising(bool with_prior);
  // A resumed checkpoint: the first cycle with odometry starts localising, with where the robot was
  // left as a candidate, if its odometry comes more than `gap_s` after the checkpoint's last sample
  // (or its time went back, or the checkpoint had none). Not part of the state: a property of the run.
  void localise_if_moved_for(double gap_s) { resume_gap_s_ = gap_s; }
  const Localiser& localiser() const { return localiser_; }

  // Adds wrong closures to the map as the front end makes its own (wrong_closures.h): a test of the
  // back end, for replays and studies. Not part of the state.
  void inject_wrong_closures(const WrongClosureParams& p) { wrong_closures_.emplace(p); }
  int64_t wrong_closures_added() const { return wrong_closures_ ? wrong_closures_->added() : 0; }

  // The decoder of a compressed camera format (MJPEG), injected by the daemon's edge; without it such
  // a frame is refused (counted in bad_images) like any format the core does not read.
  void set_frame_decoder(FrameDecoder decoder) { decoder_ = std::move(decoder); }

  // The whole state as a checkpoint blob: serialise_unsealed() + seal().
  std::vector<uint8_t> serialise() const;
  // The same in two steps, so that a daemon takes only the copy on its loop's thread and leaves the
  // checksum (a pass over every byte, ~30 MB at 10,000 templates) to the thread that writes it.
  std::vector<uint8_t> serialise_unsealed() const;
  static void seal(std::vector<uint8_t>& blob);  // appends the checksum
  // Throws std::runtime_error naming the problem: bad magic/version/checksum, truncated data, or
  // dimensions (mode, template size, pose-cell grid) that differ from `params`.
  static VitaSlam deserialise(std::span<const uint8_t> data, const SlamParams& params, const RobotGeometry& geometry);

 private:
  // The templates of one cycle and the terms they are compared by.
  struct CycleTemplates {
    std::optional<VisualTemplate> visual;
    std::optional<TactileTemplate> tactile;
    Terms terms;
  };
  // The pose cells' best estimate (cell coordinates).
  struct PoseCellBest {
    double x = 0.0, y = 0.0, theta = 0.0;
  };
  // process_cycle's four steps, in order (the numbered steps at the top of this file).
  void integrate_odometry(const std::vector<OdometrySample>& odometry);
  CycleTemplates make_templates(const CycleInput& in, CycleResult& out);
  PoseCellBest match_or_create(const CycleTemplates& templates, CycleResult& out);
  void update_map(int64_t utime, const CycleTemplates& templates, PoseCellBest& pc, CycleResult& out);
  void localise(int64_t utime, int recognised, const CycleTemplates& templates, PoseCellBest& pc, CycleResult& out);
  void move_packet_to(int experience, PoseCellBest& pc);
  // What this cycle brings the map's action rule.
  MapCycle map_cycle(int template_id, int64_t utime, const PoseCellBest& pc, int view_shift, const CycleResult& out) const;
  double tau_of(const Terms& terms) const;

  SlamParams params_;
  RobotGeometry geometry_;
  TemplateStore store_;
  PoseCells cells_;
  ExperienceMap map_;
  Localiser localiser_;
  SlamStats stats_;
  std::optional<double> resume_gap_s_;  // armed by localise_if_moved_for() until odometry comes
  double cycle_travel_m_ = 0.0;  // odometry distance of the current cycle (the localiser's give-up clock)
  int64_t last_odometry_utime_ = 0;
  bool have_odometry_time_ = false;
  bool localise_only_ = false;  // not serialised: a property of the run, not of the map
  std::optional<FrameDecoder> decoder_;  // not serialised either
  std::optional<WrongClosures> wrong_closures_;  // nor this
};

}  // namespace whiskeye::slam
