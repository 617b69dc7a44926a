// vita-eval's options (see vita_eval_app.h).
#include "vita_eval_app.h"

#include "whiskeye/eval/metrics.h"

#include <cstdio>

namespace whiskeye::eval {

void add_vita_eval_options(CLI::App& app, VitaEvalOptions& o) {
  o.position_threshold_m = kPaperCorrectPosition_m;
  o.angle_threshold_deg = kPaperCorrectAngle_deg;
  o.ate_window_laps = kAteWindowLaps;
  char default_tolerance[32];
  std::snprintf(default_tolerance, sizeof default_tolerance, "%g,%g", kFalseClosurePosition_m, kFalseClosureAngle_deg);
  o.false_closure_tolerance = default_tolerance;
  app.add_option("--input", o.inputs, "slamd output log (repeat for a multi-row table)")->required();
  app.add_option("--json", o.json_path, "write all results as JSON to this file");
  app.add_option("--plots", o.plots_dir,
                 "write plots (PNG and SVG) into this directory (created if missing): per run the experience map, "
                 "the pose trail and the re-localisations; with several runs the maps side by side");
  app.add_option("--world", o.world_path,
                 "a vita-sim world file (config/worlds/*.yaml): its walls and landmarks drawn under the plots");
  app.add_option("--start", o.start_text,
                 "X,Y,THETA_DEG: where the first pose lies in the world, for a run without ground truth "
                 "(default with --world: the world's start pose)");
  app.add_option("--trace", o.trace_dir,
                 "write a CSV per run into this directory: every cycle's event, its re-localisation's error against "
                 "ground truth and its template match (created if missing)");
  app.add_option("--tum", o.tum_dir,
                 "write each run's trajectory and its ground truth in the TUM format (timestamp x y z qx qy qz qw) "
                 "into this directory: <label>_estimate.tum (the poses ATE uses, in the map frame, unaligned) and "
                 "<label>_groundtruth.tum (created if missing)");
  app.add_option("--ate-window-laps", o.ate_window_laps,
                 "ATE also per window of this many laps of ground-truth travel")
      ->capture_default_str()
      ->check(CLI::PositiveNumber);
  app.add_option("--map-truth", o.map_truth_path,
                 "a log with the GROUND_TRUTH of the session that made the map the inputs localised in (the first "
                 "session's vita-sim or slamd output log; its clock must not overlap the inputs')")
      ->check(CLI::ExistingFile);
  app.add_flag("--session-start", o.session_start,
               "the inputs are sessions on a saved map: their start is a localisation instant (detected anyway when "
               "the map has experiences created before the log's first ground truth)");
  app.add_option("--paper-row", o.paper_names, "add the paper's Table I row: visual, tactile or vita (repeatable)")
      ->check(CLI::IsMember({"visual", "tactile", "vita"}));
  app.add_option("--centre", o.centre, "arena centre X,Y (m) for the first revolution (base set)")
      ->capture_default_str();
  app.add_option("--base-duration", o.base_duration_s,
                 "base set = experiences of the first S seconds of ground truth instead of the first revolution")
      ->check(CLI::PositiveNumber);
  app.add_option("--position-threshold", o.position_threshold_m, "ExM: correct re-localisation within this (m)")
      ->capture_default_str()
      ->check(CLI::PositiveNumber);
  app.add_option("--angle-threshold-deg", o.angle_threshold_deg, "ExM: and within this heading (deg)")
      ->capture_default_str()
      ->check(CLI::PositiveNumber);
  app.add_option("--false-closure-tolerance", o.false_closure_tolerance,
                 "M,DEG: a re-localisation is a false closure when its target was created further than M metres "
                 "or DEG degrees from the robot now (a paper-wrong one within both is a neighbour miss)")
      ->capture_default_str();
}

}  // namespace whiskeye::eval
