// slamd: the ViTa-SLAM daemon.
//   live:    slamd [--mode M] [-c FILE] [--state-dir DIR]         (LCM in and out)
//   offline: slamd --replay IN.lcmlog -o OUT.lcmlog [--mode M]    (reads the log directly)
// See docs/slamd.md. This file reads the command line and the parameters; run.h runs slamd.
#include "run.h"

#include "whiskeye/common/cli.h"
#include "whiskeye/common/params.h"
#include "whiskeye/common/robot_geometry.h"
#include "whiskeye/slam/vita_slam.h"

#include <CLI/CLI.hpp>

#include <string>
#include <vector>

using namespace whiskeye;
using slamd::Options;
using slamd::Parameters;

namespace {

// --set KEY=VALUE as an override of the config.
cli::Override set_option(const std::string& kv) {
  const size_t eq = kv.find('=');
  if (eq == 0 || eq == std::string::npos || eq + 1 == kv.size()) {
    throw ParamError("--set '" + kv + "': expected KEY=VALUE, e.g. slam.experience_map.drift_per_m=1000");
  }
  return {kv.substr(0, eq), kv.substr(eq + 1), "--set"};
}

// The parameters in use: the files, then the command line's overrides (--set, then --mode).
Parameters load_parameters(const Options& o) {
  Parameters p;
  std::vector<cli::Override> overrides;
  for (const std::string& kv : o.sets) overrides.push_back(set_option(kv));
  if (!o.mode.empty()) overrides.push_back({"slam.mode", o.mode, "--mode"});
  ParamNode root = cli::read_config(o.config, overrides);
  slam::load(root.section("slam"), p.slam);
  slamd::load(root.section("slamd"), p.node);
  root.check_no_unknown_keys();
  ParamNode robot = cli::read_config(o.robot);
  load(robot.section("robot"), p.robot);
  robot.check_no_unknown_keys();
  p.dump = root.dump() + robot.dump();
  return p;
}

}  // namespace

int main(int argc, char** argv) {
  cli::Program program("slamd", "slamd: ViTa-SLAM daemon (visuo-tactile SLAM for the WhiskEye robot)");
  CLI::App& app = program.app();
  Options o;
  program.add_config(o.config, "SLAM parameters (YAML: slam:, slamd: sections)");
  app.add_option("--robot", o.robot, "robot geometry (YAML: robot: section)")->check(CLI::ExistingFile);
  app.add_option("--mode", o.mode, "visual | tactile | vita (overrides slam.mode)");
  app.add_option("--set", o.sets, "KEY=VALUE: override one parameter of the config, e.g. "
                 "slam.experience_map.drift_per_m=1000 (repeatable; checked like the file's)");
  program.add_lcm_url(o.lcm_url);
  app.add_option("--state-dir", o.state_dir, "checkpoint directory (live default: $STATE_DIRECTORY or /var/lib/slamd)");
  app.add_option("--checkpoint-every", o.checkpoint_every, "checkpoint every N cycles (0: only on exit)")->check(CLI::NonNegativeNumber);
  app.add_option("--checkpoint-keep", o.checkpoint_keep, "checkpoints kept")->check(CLI::PositiveNumber);
  app.add_flag("--fresh", o.fresh, "ignore existing checkpoints (rotated out as new ones are written): a new map, or --map's");
  app.add_option("--map", o.map_file, "start from this saved map (a checkpoint file)")->check(CLI::ExistingFile);
  app.add_flag("--localise", o.localise, "with --map: localise in the map without growing it");
  auto* replay = app.add_option("--replay", o.replay_in, "process this LCM log offline")->check(CLI::ExistingFile);
  program.add_output(o.replay_out, "with --replay: output LCM log")->needs(replay);
  app.add_flag("--timing", o.timing, "with --replay: measure latencies into SLAM_STATUS (output no longer byte-identical)");
  app.add_option("--inject-wrong-closures", o.inject_wrong_closures,
                 "with --replay: a test of the back end: for every loop closure the SLAM makes, add one wrong one "
                 "(random: far away; local: 0.5-1.5 m off; group: 5 consecutive cycles onto an earlier pass elsewhere)")
      ->needs(replay)
      ->check(CLI::IsMember({"random", "local", "group"}));
  app.add_option("--inject-seed", o.inject_seed, "with --inject-wrong-closures: the draws' seed (default 1)");
  program.add_print_config(o.print_config);
  return program.run(argc, argv, [&] {
    if (o.localise && o.map_file.empty()) throw cli::UsageError("--localise needs --map FILE");
    if (!o.replay_in.empty() && o.replay_out.empty()) throw cli::UsageError("--replay needs --output FILE");
    // Before the output log is opened, which truncates it.
    cli::refuse_output_onto_input(
        "--output", o.replay_out,
        {{"--replay", o.replay_in}, {"--config", o.config}, {"--robot", o.robot}, {"--map", o.map_file}});
    const Parameters p = load_parameters(o);  // a ParamError (a bad file, a --mode it does not know): exit 2
    if (program.print_config(p.dump)) return 0;
    return o.replay_in.empty() ? slamd::run_live(p, o) : slamd::run_replay(p, o);
  });
}
