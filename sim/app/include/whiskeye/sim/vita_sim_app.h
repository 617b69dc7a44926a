// vita-sim's command line and what it runs: its options, in --help's order (add_vita_sim_options),
// and the mode they select (run_vita_sim): --generate-world, --bringup, --plot-world / --plot-views,
// or a simulation written as an LCM log and/or the boards' candump log. So that vita-sim's main only
// wires them, and a test drives them in-process.
#pragma once

#include "whiskeye/common/cli.h"
#include "whiskeye/sim/bringup_cli.h"
#include "whiskeye/sim/generate_cli.h"
#include "whiskeye/sim/simulator.h"

#include <cstdint>
#include <string>
#include <vector>

namespace whiskeye::sim {

// The latest first sample: a run of kMaxLaps slow laps after it still fits an int64 of microseconds.
inline constexpr int64_t kMaxStartUtime = 4'000'000'000'000'000'000;

struct VitaSimOptions {
  std::string world_path;
  std::string output;  // -o: the LCM log
  // The three configs given by no option are found by default_config_path (common/config_path.h).
  std::string robot_path;
  std::string rcp_path;  // empty: the controller's built-in defaults
  std::string plot_path;
  std::string views_path;
  std::vector<double> view_angles{90.0, 270.0, 0.0, 180.0};
  std::string frames_dir;
  int frames_every = 1;
  uint64_t seed = 1;
  double duration = 0.0;
  int64_t laps = 0;  // wide, so that an absurd count reaches the range check
  int64_t start_utime = SimParams{}.start_utime;
  double start_phase = 0.0;
  bool quiet = false;
  std::string candump_path;
  std::string whiskerd_config;
  std::string can_mode;
  std::string can_interface;
  std::string camera_format;  // empty: the world's
  int jpeg_quality = 0;       // 0: the world's
  GenerateCliOptions generate;
  BringupOptions bringup;
};

// Adds every vita-sim option to `program` (which has --help and --version), bound to `options`.
void add_vita_sim_options(cli::Program& program, VitaSimOptions& options);

// Runs what the parsed options ask for; progress and a summary on stderr. Returns the exit status
// (2 with one line on stderr for an option out of range or missing); throws ParamError for a config
// or world that is missing or wrong, and std::runtime_error for a file it cannot write (as
// cli::Program::run maps them: exit 2 and 1). `app` tells which options were given.
int run_vita_sim(const CLI::App& app, VitaSimOptions& options);

// One line per injected fault: what, when (s since `start_utime`) and what it touched.
std::string fault_summary(const FaultRecord& f, int64_t start_utime);

}  // namespace whiskeye::sim
