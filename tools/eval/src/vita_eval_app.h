// vita-eval's command line and what it runs: its options, in --help's order (add_vita_eval_options),
// and the evaluation they ask for (run_vita_eval): every input log evaluated into a table row, then
// the table printed and the JSON, plots, traces and TUM trajectories written. So that vita-eval's main only wires them.
#pragma once

#include <CLI/CLI.hpp>

#include <string>
#include <vector>

namespace whiskeye::eval {

struct VitaEvalOptions {
  std::vector<std::string> inputs;
  std::string json_path;
  std::string plots_dir;
  std::string trace_dir;
  std::string tum_dir;
  double ate_window_laps = 0.0;  // the default set by add_vita_eval_options
  std::string world_path;
  std::string start_text;  // X,Y,THETA_DEG
  std::vector<std::string> paper_names;
  std::string centre = "0,0";
  double position_threshold_m = 0.0;   // the paper's, set by add_vita_eval_options
  double angle_threshold_deg = 0.0;    // the paper's, set by add_vita_eval_options
  std::string false_closure_tolerance;  // M,DEG; the default set by add_vita_eval_options
  double base_duration_s = -1.0;        // > 0: the base set by time, not by the first revolution
  std::string map_truth_path;
  bool session_start = false;
};

// Adds every vita-eval option to `app`, bound to `options`, and sets the defaults they show.
void add_vita_eval_options(CLI::App& app, VitaEvalOptions& options);

// Refuses (cli::UsageError: exit 2) `path`, a file vita-eval is to write, given by `option`, when it
// is one of the files it reads: an --input, the --map-truth log, the --world (the same file, by
// device and inode). Called before each output is opened.
void refuse_output_onto_input(const VitaEvalOptions& options, const std::string& option, const std::string& path);

// Evaluates, prints the table to stdout and writes what was asked for; what each input lacks or lost
// on stderr. Returns the exit status (2 with one line on stderr for a bad option value or world);
// throws std::runtime_error for a log it cannot read or a file it cannot write (exit 1), and
// cli::UsageError for an output that is one of its inputs or (--json) cannot be written there (exit 2).
int run_vita_eval(const VitaEvalOptions& options);

}  // namespace whiskeye::eval
