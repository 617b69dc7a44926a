// vita-sim's generate mode (see generate_cli.h).
#include "whiskeye/sim/generate_cli.h"

#include "whiskeye/common/config_path.h"
#include "whiskeye/common/output_file.h"
#include "whiskeye/common/params.h"
#include "whiskeye/slam/vita_slam.h"

#include <iostream>
#include <stdexcept>

namespace whiskeye::sim {

namespace {

// "MIN,MAX" (or one number for both) of a generator option; GeneratorOptionError naming it.
Range parse_range(const std::string& option, const std::string& text) {
  const auto comma = text.find(',');
  const std::string a = text.substr(0, comma);
  const std::string b = comma == std::string::npos ? a : text.substr(comma + 1);
  Range r;
  try {
    std::size_t ia = 0;
    std::size_t ib = 0;
    r.min = std::stod(a, &ia);
    r.max = std::stod(b, &ib);
    if (ia != a.size() || ib != b.size()) throw std::invalid_argument("trailing text");
  } catch (const std::exception&) {
    throw GeneratorOptionError(option + ": expected MIN,MAX (or one number), got '" + text + "'");
  }
  return r;
}

}  // namespace

void add_generate_options(CLI::App& app, GenerateCliOptions& o, const std::string& default_config_dirs) {
  o.ranges = {
      {"--arena-side", "Generated world: arena side range MIN,MAX (m; 5,8)", &GeneratorOptions::side, ""},
      {"--radius", "Generated world: trajectory radius range MIN,MAX (m; 0.8,1.3)", &GeneratorOptions::radius, ""},
      {"--speed", "Generated world: tangential speed range MIN,MAX (m/s; 0.07,0.15)", &GeneratorOptions::speed, ""},
      {"--gen-laps", "Generated world: laps range MIN,MAX (4,10)", &GeneratorOptions::laps, ""},
      {"--wall-landmarks", "Generated world: wall landmarks MIN,MAX (4,8)", &GeneratorOptions::wall_landmarks, ""},
      {"--tactile-landmarks", "Generated world: tactile landmarks MIN,MAX (3,6)", &GeneratorOptions::tactile_landmarks,
       ""}};
  app.add_flag("--generate-world", o.generate,
               "Draw a world (--world-seed, --family), check its aliasing and write it to --output-world; no simulation");
  app.add_option("--world-seed", o.generator.world_seed, "Seed of the generated world")->capture_default_str();
  app.add_option("--output-world", o.output_world, "YAML file the generated world is written to");
  app.add_option("--output-world-json", o.output_world_json,
                 "Also write the generated world's header and drawn parameters to this JSON file");
  app.add_option("--family", o.generator.family,
                 "Generated world family: aliased (the paper's premise) or stress (premise broken)")
      ->capture_default_str();
  app.add_flag("--faults", o.generator.faults,
               "Generated world: add the standard sensor faults (4 dead whiskers, a board offline 30 s, a 10 s camera "
               "blackout, a 20 % odometry slip for 10 s)");
  app.add_option("--kidnaps", o.generator.kidnaps,
                 "Generated world: draw N kidnaps (0.." + std::to_string(kMaxKidnaps) +
                     ") after the first lap, a lap apart where the run allows, each 90-270 deg along the path from "
                     "where the robot is");
  app.add_option("--slam-config", o.slam_config,
                 "slamd config whose visual template and match threshold the check uses (default: slam.yaml" +
                     default_config_dirs);
  for (RangeOption& r : o.ranges) app.add_option(r.name, r.text, r.help);
}

int run_generate(const GenerateCliOptions& cli, const RobotGeometry& robot, const rcp::ControllerParams& controller,
                 bool quiet) {
  GeneratorOptions options = cli.generator;
  const std::vector<RangeOption>& ranges = cli.ranges;
  const std::string& output_world = cli.output_world;
  const std::string& output_json = cli.output_world_json;
  const std::string slam_config =
      cli.slam_config.empty() ? default_config_path("slam.yaml", "--slam-config").string() : cli.slam_config;
  try {
    for (const RangeOption& r : ranges) {
      if (!r.text.empty()) options.*r.field = parse_range(r.name, r.text);
    }
    validate(options);
  } catch (const GeneratorOptionError& e) {
    std::cerr << "vita-sim: " << e.what() << "\n";
    return 2;
  }
  if (output_world.empty()) {
    std::cerr << "vita-sim: --generate-world needs --output-world FILE\n";
    return 2;
  }
  AliasCheckParams check;
  {
    const ParamNode root = ParamNode::from_file(slam_config);
    slam::SlamParams slam;
    slam::load(root.section("slam"), slam);
    check.visual = slam.visual;
    check.match = slam.match;
  }
  check.whisking = controller.pattern;
  GeneratedWorld g;
  try {
    g = generate_world(options, robot, check);
  } catch (const GeneratorOptionError& e) {  // a request no world can meet, said before any draw
    std::cerr << "vita-sim: " << e.what() << "\n";
    return 2;
  }
  // A later run (vita-sim --world, the suite) reads both: the old file or the new one, never part.
  write_file_atomically(output_world, g.yaml);
  if (!output_json.empty()) write_file_atomically(output_json, g.json);
  if (!quiet) {
    std::cerr << "vita-sim: wrote " << output_world << " (" << options.family << ", world seed " << options.world_seed
              << ", draw " << g.attempts << "): " << g.report.place_pairs.size() << " look-alike pairs of places, "
              << g.world.solids.size() << " tactile landmarks\n";
  }
  return 0;
}

}  // namespace whiskeye::sim
