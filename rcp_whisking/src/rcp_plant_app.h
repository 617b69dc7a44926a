// rcp-plant's command line and what it runs: its options, in --help's order (add_rcp_plant_options),
// and the experiment they describe (run_rcp_plant): the controller's config and the scenario with
// the command line's overrides, the flag obstacle, the run with and without RCP, its JSON. So that
// rcp-plant's main only wires them.
#pragma once

#include <whiskeye/common/cli.h>

#include <cstdint>
#include <optional>
#include <string>

namespace whiskeye::rcp {

struct RcpPlantOptions {
  std::string config_path;
  std::string scenario_path;
  int cycles = 20;
  int warmup = 1;
  uint64_t seed = 1;
  std::string whiskers_text;
  std::optional<double> contact_angle_deg;
  std::optional<double> radial_distance;
  std::optional<double> stiffness;
  // Overrides of config keys: the text as given, read by the key's loader (its type and range checks).
  std::string law;
  std::string noise;
  std::string frequency;
  bool no_compare = false;
  bool print_config = false;
  bool print_params = false;
};

// Adds every rcp-plant option to `program` (which has --help and --version), bound to `options`.
void add_rcp_plant_options(cli::Program& program, RcpPlantOptions& options);

// Runs the experiment and prints its JSON to stdout (or, with --print-config, the parameters). Returns
// the exit status; a bad option or file throws cli::UsageError or ParamError (exit 2). `app` tells
// which options were given.
int run_rcp_plant(const CLI::App& app, const RcpPlantOptions& options);

}  // namespace whiskeye::rcp
