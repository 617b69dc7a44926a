// vita-sim's generate mode (--generate-world): its options, and the draw written to --output-world
// (and --output-world-json) (docs/simulator.md, "Generated worlds"). So that vita-sim's main only
// wires them.
#pragma once

#include "whiskeye/common/robot_geometry.h"
#include "whiskeye/rcp/params.h"
#include "whiskeye/sim/world_generator.h"

#include <CLI/CLI.hpp>

#include <string>
#include <vector>

namespace whiskeye::sim {

// A drawing range of the generator as a command-line option: "MIN,MAX" text into a Range field.
struct RangeOption {
  const char* name;
  const char* help;
  Range GeneratorOptions::*field;
  std::string text;
};

struct GenerateCliOptions {
  bool generate = false;  // --generate-world
  GeneratorOptions generator;
  std::string output_world;
  std::string output_world_json;
  std::string slam_config;  // empty: slam.yaml from the default config directories
  std::vector<RangeOption> ranges;
};

// Adds --generate-world and the generator's options, in --help's order. `default_config_dirs` ends
// the help of --slam-config (where its default is looked for).
void add_generate_options(CLI::App& app, GenerateCliOptions& options, const std::string& default_config_dirs);

// Draws, checks and writes the world; progress on stderr unless `quiet`. Returns the exit status:
// 2 with one line for a bad option or a request no world can meet; throws on a file not written.
int run_generate(const GenerateCliOptions& options, const RobotGeometry& robot, const rcp::ControllerParams& controller,
                 bool quiet);

}  // namespace whiskeye::sim
