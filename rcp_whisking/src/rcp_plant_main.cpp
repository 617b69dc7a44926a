// rcp-plant: runs the whisking controller against the whisker plant model for N cycles with an
// obstacle and prints JSON (contact rate, peak base deflection with and without RCP, reaction
// latency, false contacts) — how a user tunes RCP without a robot. See docs/rcp-whisking.md.
#include <whiskeye/common/cli.h>
#include <whiskeye/rcp/experiment.h>

#include <CLI/CLI.hpp>

#include <cstdio>
#include <iostream>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

namespace {

using namespace whiskeye;
using namespace whiskeye::rcp;

void print_metrics(std::ostream& out, const RunMetrics& m, const std::string& indent) {
  out << "{\n"
      << indent << "  \"cycles_measured\": " << m.cycles_measured << ",\n"
      << indent << "  \"whisker_cycles_with_obstacle\": " << m.whisker_cycles_with_obstacle << ",\n"
      << indent << "  \"whisker_cycles_with_contact\": " << m.whisker_cycles_with_contact << ",\n"
      << indent << "  \"contact_rate\": " << m.contact_rate << ",\n"
      << indent << "  \"peak_deflection\": " << m.peak_deflection << ",\n"
      << indent << "  \"mean_cycle_peak_deflection\": " << m.mean_cycle_peak_deflection << ",\n"
      << indent << "  \"reaction_latency_mean_ms\": " << m.reaction_latency_mean * 1e3 << ",\n"
      << indent << "  \"reaction_latency_max_ms\": " << m.reaction_latency_max * 1e3 << ",\n"
      << indent << "  \"controller_latency_max_ms\": " << m.controller_latency_max * 1e3 << ",\n"
      << indent << "  \"reactions\": " << m.reactions << ",\n"
      << indent << "  \"contact_onsets\": " << m.contact_onsets << ",\n"
      << indent << "  \"false_contacts\": " << m.false_contacts << "\n"
      << indent << "}";
}

std::vector<int> parse_whiskers(const std::string& text) {
  std::vector<int> out;
  if (text == "all") {
    for (int w = 0; w < kNumWhiskers; ++w) out.push_back(w);
    return out;
  }
  std::stringstream ss(text);
  std::string item;
  while (std::getline(ss, item, ',')) {
    std::size_t used = 0;
    int w = -1;
    try {
      w = std::stoi(item, &used);
    } catch (const std::exception&) {
      used = 0;
    }
    if (used != item.size() || w < 0 || w >= kNumWhiskers) {
      throw cli::UsageError("--whiskers: '" + item + "' is not a whisker index 0..23");
    }
    out.push_back(w);
  }
  return out;
}

}  // namespace

int main(int argc, char** argv) {
  cli::Program program("rcp-plant",
                       "rcp-plant: run the whisking controller (pattern, contact detection, RCP) against the whisker "
                       "plant model with an obstacle and print JSON figures: contact rate, peak base deflection with "
                       "and without RCP, reaction latency, false contacts.");
  CLI::App& app = program.app();
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
  program.add_config(config_path, "controller parameters YAML (sections pattern, detector, rcp; e.g. config/rcp.yaml)");
  app.add_option("--scenario", scenario_path,
                 "scenario YAML: sections plant (PlantParams), run (cycles, warmup_cycles, seed), list obstacles "
                 "(whiskers, contact_angle_deg, radial_distance, stiffness_scale, deflection_direction_deg)")
      ->check(CLI::ExistingFile);
  app.add_option("--cycles", cycles, "whisk cycles to run, overrides run.cycles (default 20)")->check(CLI::Range(2, 100000));
  app.add_option("--warmup", warmup, "first cycles left out of the figures, overrides run.warmup_cycles (default 1)")
      ->check(CLI::Range(0, 1000));
  app.add_option("--seed", seed, "plant noise seed, overrides run.seed (default 1)");
  app.add_option("--whiskers", whiskers_text, "whiskers with the flag obstacle: 'all' or e.g. 0,6,12 (default all)");
  app.add_option("--contact-angle-deg", contact_angle_deg, "obstacle: protraction angle of first touch, deg (default 10)");
  app.add_option("--radial-distance", radial_distance, "obstacle: radial contact distance from the base, m (default 0.05)");
  app.add_option("--stiffness", stiffness, "obstacle: stiffness scale (default 1)");
  app.add_option("--law", law, "overrides rcp.law")->check(CLI::IsMember({"whiskeye", "rate_limited", "off"}));
  app.add_option("--noise", noise, "overrides plant.noise_sigma (Hall x/y, calibrated units)");
  app.add_option("--frequency-hz", frequency, "overrides pattern.frequency_hz");
  app.add_flag("--no-compare", no_compare, "skip the run without RCP");
  program.add_print_config(print_config);
  app.add_flag("--print-params", print_params, "print every parameter in use to stderr, then run");
  return program.run(argc, argv, [&] {
    ControllerParams cp;
    PlantParams pp;
    ExperimentSpec spec;
    spec.cycles = cycles;
    spec.warmup_cycles = warmup;
    spec.seed = seed;

    // The files, then the command line's overrides: --print-config shows what a run uses.
    ParamNode config = config_path.empty() ? ParamNode::empty() : ParamNode::from_file(config_path);
    if (!law.empty()) config.set_override("rcp.law", law, "--law");
    if (!frequency.empty()) config.set_override("pattern.frequency_hz", frequency, "--frequency-hz");
    load(config, cp);  // validates the overrides too
    config.check_no_unknown_keys();

    ParamNode scenario = scenario_path.empty() ? ParamNode::empty("<no --scenario>") : ParamNode::from_file(scenario_path);
    if (!noise.empty()) scenario.set_override("plant.noise_sigma", noise, "--noise");
    if (app.count("--cycles")) scenario.set_override("run.cycles", std::to_string(cycles), "--cycles");
    if (app.count("--warmup")) scenario.set_override("run.warmup_cycles", std::to_string(warmup), "--warmup");
    if (app.count("--seed")) scenario.set_override("run.seed", std::to_string(seed), "--seed");
    load(scenario.section("plant"), pp);
    const ParamNode run = scenario.section("run");
    run.get("cycles", spec.cycles, 2, 100000);
    run.get("warmup_cycles", spec.warmup_cycles, 0, 1000);
    run.get("seed", spec.seed);
    for (const ParamNode& item : scenario.list("obstacles")) {
      std::vector<int> ws;
      item.require("whiskers", ws);
      Obstacle o;
      double angle_deg = 10.0;
      item.require("contact_angle_deg", angle_deg);
      o.contact_angle = deg_to_rad(angle_deg);
      item.require("radial_distance", o.radial_distance);
      item.get("stiffness_scale", o.stiffness_scale, 0.0, 100.0);
      double dir_deg = 180.0;
      item.get("deflection_direction_deg", dir_deg, -360.0, 360.0);
      o.deflection_direction = deg_to_rad(dir_deg);
      for (int w : ws) {
        if (w < 0 || w >= kNumWhiskers) throw ParamError(scenario_path + ": 'obstacles.whiskers' index " + std::to_string(w) + " is not 0..23");
        spec.obstacles[w] = o;
      }
    }
    scenario.check_no_unknown_keys();

    // The obstacle the flags describe: on every whisker without a scenario, else on --whiskers.
    Obstacle flag_obstacle;
    flag_obstacle.contact_angle = deg_to_rad(10.0);
    const bool flag_obstacles =
        scenario_path.empty() || !whiskers_text.empty() || contact_angle_deg || radial_distance || stiffness;
    std::string flags_dump;
    if (flag_obstacles) {
      if (contact_angle_deg) flag_obstacle.contact_angle = deg_to_rad(*contact_angle_deg);
      if (radial_distance) flag_obstacle.radial_distance = *radial_distance;
      if (stiffness) flag_obstacle.stiffness_scale = *stiffness;
      const std::string whiskers = whiskers_text.empty() ? "all" : whiskers_text;
      for (int w : parse_whiskers(whiskers)) spec.obstacles[w] = flag_obstacle;
      std::ostringstream line;
      line << "flag obstacle: whiskers " << whiskers << ", contact_angle_deg " << rad_to_deg(flag_obstacle.contact_angle)
           << ", radial_distance " << flag_obstacle.radial_distance << ", stiffness_scale "
           << flag_obstacle.stiffness_scale << "\n";
      flags_dump = line.str();
    }
    if (spec.cycles <= spec.warmup_cycles) throw cli::UsageError("--cycles must exceed --warmup");
    spec.compare_without_rcp = !no_compare;
    const std::string dump = config.dump() + scenario.dump() + flags_dump;
    if (print_config) {
      std::cout << dump;
      return 0;
    }
    if (print_params) std::cerr << dump;

    const ExperimentResult r = run_experiment(cp, pp, spec);
    std::cout.precision(6);
    std::cout << "{\n  \"law\": \"" << to_string(cp.rcp.law) << "\",\n  \"frequency_hz\": " << cp.pattern.frequency_hz
              << ",\n  \"cycles\": " << spec.cycles << ",\n  \"seed\": " << spec.seed << ",\n  \"with_rcp\": ";
    print_metrics(std::cout, r.rcp, "  ");
    if (r.without_rcp) {
      std::cout << ",\n  \"without_rcp\": ";
      print_metrics(std::cout, *r.without_rcp, "  ");
      std::cout << ",\n  \"peak_reduction\": " << r.peak_reduction;
    }
    std::cout << "\n}\n";
    return 0;
  });
}
