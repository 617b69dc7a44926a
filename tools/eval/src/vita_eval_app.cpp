// What vita-eval runs (see vita_eval_app.h).
#include "vita_eval_app.h"

#include "log_input.h"
#include "plots.h"
#include "report.h"

#include "whiskeye/common/cli.h"
#include "whiskeye/common/output_file.h"
#include "whiskeye/eval/metrics.h"
#include "whiskeye/eval/options.h"
#include "whiskeye/sim/world.h"

#include <cstdio>
#include <exception>
#include <filesystem>
#include <iostream>
#include <optional>
#include <set>
#include <sstream>
#include <stdexcept>

namespace whiskeye::eval {

namespace {

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

// Writes `text` to `path` atomically (the suite reads the JSON); throws naming the file if it cannot.
void write_text(const std::string& path, const std::string& text) { write_file_atomically(path, text); }

// The metrics' parameters from the options. Returns 0, or 2 with one line on stderr.
int eval_params(const VitaEvalOptions& o, EvalParams& params) {
  params.correct_position_m = o.position_threshold_m;
  params.correct_angle_rad = deg_to_rad(o.angle_threshold_deg);
  if (const std::string error = parse_false_closure_tolerance(o.false_closure_tolerance, params); !error.empty()) {
    std::cerr << "vita-eval: " << error << "\n";
    return 2;
  }
  if (!parse_centre(o.centre, params.centre_x, params.centre_y)) {
    std::cerr << "vita-eval: --centre must be X,Y in metres, got '" << o.centre << "'\n";
    return 2;
  }
  params.ate_window_laps = o.ate_window_laps;
  if (o.base_duration_s > 0) params.base_duration_s = o.base_duration_s;
  params.session_start = o.session_start;
  return 0;
}

// One input log evaluated: its row of the table, its input kept for the plots and traces; what it
// lacks or lost on stderr. `labels` holds the rows' labels so far (a mode twice: "vita#2").
RunReport evaluate_input(const std::string& path, const std::vector<PoseSample>& map_truth,
                         const std::string& map_truth_path, const EvalParams& params, std::set<std::string>& labels,
                         EvalInput& input) {
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
  r.map_links_revoked = run.input.map.revoked_links();
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
  input = std::move(run.input);
  return r;
}

// The plots, the TUM trajectories and the per-cycle traces, where asked for; none of them onto a file
// read (the TUM files' and traces' names checked before anything is written, each plot's before it is).
void write_plots_and_traces(const VitaEvalOptions& o, const std::vector<RunReport>& reports,
                            const std::vector<EvalInput>& inputs, const PlotScene& scene) {
  std::vector<std::string> tums, traces;
  for (const RunReport& r : reports) {
    if (!o.tum_dir.empty()) {
      const std::string stem = (std::filesystem::path(o.tum_dir) / plot_stem(r.label)).string();
      for (const char* suffix : {"_estimate.tum", "_groundtruth.tum"}) {
        tums.push_back(stem + suffix);
        refuse_output_onto_input(o, "--tum", tums.back());
      }
    }
    if (!o.trace_dir.empty()) {
      traces.push_back((std::filesystem::path(o.trace_dir) / (plot_stem(r.label) + "_trace.csv")).string());
      refuse_output_onto_input(o, "--trace", traces.back());
    }
  }
  if (!o.plots_dir.empty()) {
    std::filesystem::create_directories(o.plots_dir);
    std::vector<PlotRun> runs;
    const auto not_an_input = [&](const std::string& path) { refuse_output_onto_input(o, "--plots", path); };
    for (std::size_t i = 0; i < reports.size(); ++i) {
      runs.push_back({reports[i].label, &inputs[i], &reports[i].result});
      plot_run(o.plots_dir, runs.back(), scene, not_an_input);
    }
    if (runs.size() > 1) plot_comparison(o.plots_dir, runs, scene, not_an_input);
  }
  if (!o.tum_dir.empty()) {
    std::filesystem::create_directories(o.tum_dir);
    for (std::size_t i = 0; i < reports.size(); ++i) {
      write_text(tums[2 * i], format_tum(claimed_poses(inputs[i].estimate, inputs[i].states)));
      write_text(tums[2 * i + 1], format_tum(GroundTruth(inputs[i].ground_truth).samples()));
    }
  }
  if (!o.trace_dir.empty()) {
    std::filesystem::create_directories(o.trace_dir);
    for (std::size_t i = 0; i < reports.size(); ++i) {
      const auto* localisation = reports[i].result.localisation ? &*reports[i].result.localisation : nullptr;
      write_text(traces[i], format_trace_csv(trace_cycles(inputs[i], reports[i].result.exm, localisation)));
    }
  }
}

}  // namespace

void refuse_output_onto_input(const VitaEvalOptions& o, const std::string& option, const std::string& path) {
  std::vector<cli::InputFile> read{{"--map-truth", o.map_truth_path}, {"--world", o.world_path}};
  for (const std::string& input : o.inputs) read.push_back({"--input", input});
  cli::refuse_output_onto_input(option, path, read);
}

int run_vita_eval(const VitaEvalOptions& o) {
  EvalParams params;
  if (const int status = eval_params(o, params); status != 0) return status;
  if (!o.json_path.empty()) {
    refuse_output_onto_input(o, "--json", o.json_path);
    cli::refuse_unwritable_output("--json", o.json_path);
  }
  std::vector<PoseSample> map_truth;
  if (!o.map_truth_path.empty()) map_truth = load_ground_truth(o.map_truth_path);
  PlotScene scene;
  scene.params = params;
  Pose2 start;
  if (!o.start_text.empty()) {
    if (!parse_start(o.start_text, start)) {
      std::cerr << "vita-eval: --start must be X,Y,THETA_DEG (m, m, degrees), got '" << o.start_text << "'\n";
      return 2;
    }
    scene.start = start;
  }
  std::optional<sim::World> world;
  if (!o.world_path.empty()) {
    try {
      world = sim::load_world_file(o.world_path);
    } catch (const std::exception& e) {
      std::cerr << "vita-eval: --world " << o.world_path << ": " << e.what() << "\n";
      return 2;
    }
    scene.world = &*world;
  }

  std::vector<RunReport> reports;
  std::vector<EvalInput> inputs;
  std::set<std::string> labels;
  for (const std::string& path : o.inputs) {
    EvalInput input;
    reports.push_back(evaluate_input(path, map_truth, o.map_truth_path, params, labels, input));
    inputs.push_back(std::move(input));
  }

  std::vector<PaperRow> paper;
  for (const std::string& name : o.paper_names) paper.push_back(*paper_row(name));
  std::cout << format_table(reports, params, paper);
  if (!o.json_path.empty()) write_text(o.json_path, to_json(reports, params, paper).dump(2) + "\n");
  write_plots_and_traces(o, reports, inputs, scene);
  return 0;
}

}  // namespace whiskeye::eval
