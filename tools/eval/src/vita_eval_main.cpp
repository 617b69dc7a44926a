// vita-eval: the paper's Table I metrics (LEM, ExM, EnM; ../shared/design/metrics.md), and the false
// closures beside ARCR, from one or more slamd output logs. Prints the table, optionally writes JSON,
// plots (PNG and SVG, optionally over a vita-sim world) and per-cycle traces. A log without GROUND_TRUTH (a real robot's run) is
// drawn and counted; what needs truth is reported as unavailable.
#include "log_input.h"
#include "plots.h"
#include "report.h"

#include "whiskeye/common/cli.h"
#include "whiskeye/eval/metrics.h"
#include "whiskeye/eval/options.h"
#include "whiskeye/sim/world.h"

#include <CLI/CLI.hpp>

#include <cstdio>
#include <exception>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <set>
#include <sstream>
#include <stdexcept>

namespace {

using namespace whiskeye;
using namespace whiskeye::eval;

bool parse_centre(const std::string& text, double& x, double& y) {
  std::istringstream in(text);
  char comma = 0;
  return static_cast<bool>(in >> x >> comma >> y) && comma == ',' && (in >> std::ws).eof();
}

bool parse_start(const std::string& text, Pose2& pose) {
  std::istringstream in(text);
  char c1 = 0, c2 = 0;
  double deg = 0.0;
  if (!(in >> pose.x >> c1 >> pose.y >> c2 >> deg) || c1 != ',' || c2 != ',' || !(in >> std::ws).eof()) return false;
  pose.theta = wrap_angle(deg_to_rad(deg));
  return true;
}

// Writes `text` to `path`; throws naming the file if it cannot.
void write_text(const std::string& path, const std::string& text) {
  std::ofstream out(path);
  out << text;
  if (!out) throw std::runtime_error("cannot write " + path);
}

int run(int argc, char** argv) {
  cli::Program program("vita-eval",
                       "vita-eval: LEM, ExM (ARR, ARCR, valid fraction) and EnM of slamd output logs against "
                       "their GROUND_TRUTH, as in the paper's Table I, and plots of any run, with or without ground "
                       "truth (see docs/evaluation.md)");
  CLI::App& app = program.app();
  std::vector<std::string> inputs;
  std::string json_path;
  std::string plots_dir;
  std::string trace_dir;
  std::string world_path;
  std::string start_text;
  std::vector<std::string> paper_names;
  std::string centre = "0,0";
  double position_threshold_m = kPaperCorrectPosition_m;
  double angle_threshold_deg = kPaperCorrectAngle_deg;
  char default_tolerance[32];
  std::snprintf(default_tolerance, sizeof default_tolerance, "%g,%g", kFalseClosurePosition_m, kFalseClosureAngle_deg);
  std::string false_closure_tolerance = default_tolerance;
  double base_duration_s = -1.0;
  std::string map_truth_path;
  bool session_start = false;
  app.add_option("--input", inputs, "slamd output log (repeat for a multi-row table)")->required();
  app.add_option("--json", json_path, "write all results as JSON to this file");
  app.add_option("--plots", plots_dir,
                 "write plots (PNG and SVG) into this directory (created if missing): per run the experience map, "
                 "the pose trail and the re-localisations; with several runs the maps side by side");
  app.add_option("--world", world_path,
                 "a vita-sim world file (config/worlds/*.yaml): its walls and landmarks drawn under the plots");
  app.add_option("--start", start_text,
                 "X,Y,THETA_DEG: where the first pose lies in the world, for a run without ground truth "
                 "(default with --world: the world's start pose)");
  app.add_option("--trace", trace_dir,
                 "write a CSV per run into this directory: every cycle's event, its re-localisation's error against "
                 "ground truth and its template match (created if missing)");
  app.add_option("--map-truth", map_truth_path,
                 "a log with the GROUND_TRUTH of the session that made the map the inputs localised in (the first "
                 "session's vita-sim or slamd output log; its clock must not overlap the inputs')")
      ->check(CLI::ExistingFile);
  app.add_flag("--session-start", session_start,
               "the inputs are sessions on a saved map: their start is a localisation instant (detected anyway when "
               "the map has experiences created before the log's first ground truth)");
  app.add_option("--paper-row", paper_names, "add the paper's Table I row: visual, tactile or vita (repeatable)")
      ->check(CLI::IsMember({"visual", "tactile", "vita"}));
  app.add_option("--centre", centre, "arena centre X,Y (m) for the first revolution (base set)")
      ->capture_default_str();
  app.add_option("--base-duration", base_duration_s,
                 "base set = experiences of the first S seconds of ground truth instead of the first revolution")
      ->check(CLI::PositiveNumber);
  app.add_option("--position-threshold", position_threshold_m, "ExM: correct re-localisation within this (m)")
      ->capture_default_str()
      ->check(CLI::PositiveNumber);
  app.add_option("--angle-threshold-deg", angle_threshold_deg, "ExM: and within this heading (deg)")
      ->capture_default_str()
      ->check(CLI::PositiveNumber);
  app.add_option("--false-closure-tolerance", false_closure_tolerance,
                 "M,DEG: a re-localisation is a false closure when its target was created further than M metres "
                 "or DEG degrees from the robot now (a paper-wrong one within both is a neighbour miss)")
      ->capture_default_str();
  return program.run(argc, argv, [&] {
    EvalParams params;
    params.correct_position_m = position_threshold_m;
    params.correct_angle_rad = deg_to_rad(angle_threshold_deg);
    if (const std::string error = parse_false_closure_tolerance(false_closure_tolerance, params); !error.empty()) {
      std::cerr << "vita-eval: " << error << "\n";
      return 2;
    }
    if (!parse_centre(centre, params.centre_x, params.centre_y)) {
      std::cerr << "vita-eval: --centre must be X,Y in metres, got '" << centre << "'\n";
      return 2;
    }
    if (base_duration_s > 0) params.base_duration_s = base_duration_s;
    params.session_start = session_start;
    std::vector<PoseSample> map_truth;
    if (!map_truth_path.empty()) map_truth = load_ground_truth(map_truth_path);
    PlotScene scene;
    scene.params = params;
    Pose2 start;
    if (!start_text.empty()) {
      if (!parse_start(start_text, start)) {
        std::cerr << "vita-eval: --start must be X,Y,THETA_DEG (m, m, degrees), got '" << start_text << "'\n";
        return 2;
      }
      scene.start = start;
    }
    std::optional<sim::World> world;
    if (!world_path.empty()) {
      try {
        world = sim::load_world_file(world_path);
      } catch (const std::exception& e) {
        std::cerr << "vita-eval: --world " << world_path << ": " << e.what() << "\n";
        return 2;
      }
      scene.world = &*world;
    }

    std::vector<RunReport> reports;
    std::vector<EvalInput> loaded_inputs;
    std::set<std::string> labels;
    for (const std::string& path : inputs) {
      LoadedRun run = load_run(path);
      RunReport r;
      r.label = run.mode;
      for (int n = 2; labels.count(r.label) > 0; ++n) r.label = run.mode + "#" + std::to_string(n);
      labels.insert(r.label);
      r.path = path;
      r.mode = run.mode;
      r.pose_samples = run.input.estimate.size();
      r.events = run.input.events.size();
      r.map_experiences = run.input.map.experiences.size();
      r.map_links = run.input.map.links.size();
      r.ground_truth_samples = run.input.ground_truth.size();
      r.decode_errors = run.decode_errors;
      r.log_damage = run.log_damage;
      r.faults = run.input.faults;
      r.start_utime = run_start_utime(run.input);
      if (!map_truth.empty() && !run.input.ground_truth.empty()) {
        const GroundTruth own(run.input.ground_truth);
        const GroundTruth earlier(map_truth);
        if (own.begin_utime() <= earlier.end_utime() && earlier.begin_utime() <= own.end_utime()) {
          throw std::runtime_error("--map-truth " + map_truth_path + ": its ground truth overlaps " + path +
                                   "'s in time (a second session needs a later clock: vita-sim --start-utime)");
        }
        run.input.map_ground_truth = map_truth;
      }
      if (!r.log_damage.empty()) std::cerr << "vita-eval: " << r.log_damage << " (evaluated what could be read)\n";
      r.result = evaluate(run.input, params);
      for (const auto& [ch, n] : run.decode_errors) {
        std::cerr << "vita-eval: " << path << ": " << n << " undecodable messages on " << ch << "\n";
      }
      if (!r.result.ground_truth) {
        std::cerr << "vita-eval: " << path
                  << ": no GROUND_TRUTH: the metrics that need it (EnM, ARCR, LEM, valid fraction) are unavailable\n";
      } else if (!r.result.alignment.valid) {
        std::cerr << "vita-eval: " << path << ": " << r.result.alignment.reason << "\n";
      }
      if (r.result.localisation && run.input.map_ground_truth.empty()) {
        for (const Localisation& l : r.result.localisation->instants) {
          if (l.instant.kind != LocalisationInstant::Kind::kSessionStart) continue;
          std::cerr << "vita-eval: " << path
                    << ": a session on a saved map without the map's session's ground truth: its experiences "
                       "cannot be judged (--map-truth)\n";
        }
      }
      if (r.result.ground_truth && !r.result.exm.base_end_found) {
        std::cerr << "vita-eval: " << path
                  << ": ground truth never completes a revolution around the centre; every experience is in "
                     "the base set (use --centre or --base-duration)\n";
      }
      reports.push_back(std::move(r));
      loaded_inputs.push_back(std::move(run.input));
    }

    std::vector<PaperRow> paper;
    for (const std::string& name : paper_names) paper.push_back(*paper_row(name));

    std::cout << format_table(reports, params, paper);

    if (!json_path.empty()) write_text(json_path, to_json(reports, params, paper).dump(2) + "\n");
    if (!plots_dir.empty()) {
      std::filesystem::create_directories(plots_dir);
      std::vector<PlotRun> runs;
      for (std::size_t i = 0; i < reports.size(); ++i) {
        runs.push_back({reports[i].label, &loaded_inputs[i], &reports[i].result});
        plot_run(plots_dir, runs.back(), scene);
      }
      if (runs.size() > 1) plot_comparison(plots_dir, runs, scene);
    }
    if (!trace_dir.empty()) {
      std::filesystem::create_directories(trace_dir);
      for (std::size_t i = 0; i < reports.size(); ++i) {
        write_text((std::filesystem::path(trace_dir) / (plot_stem(reports[i].label) + "_trace.csv")).string(),
                   format_trace_csv(trace_cycles(loaded_inputs[i], reports[i].result.exm,
                                                 reports[i].result.localisation ? &*reports[i].result.localisation
                                                                                : nullptr)));
      }
    }
    return 0;
  });
}

}  // namespace

int main(int argc, char** argv) { return run(argc, argv); }
