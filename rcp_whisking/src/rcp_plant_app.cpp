// What rcp-plant runs (see rcp_plant_app.h).
#include "rcp_plant_app.h"

#include <whiskeye/rcp/experiment.h>

#include <CLI/CLI.hpp>

#include <iostream>
#include <sstream>
#include <string>
#include <vector>

namespace whiskeye::rcp {

namespace {

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

int run_rcp_plant(const CLI::App& app, const RcpPlantOptions& opt) {
  ControllerParams cp;
  PlantParams pp;
  ExperimentSpec spec;
  spec.cycles = opt.cycles;
  spec.warmup_cycles = opt.warmup;
  spec.seed = opt.seed;

  // The files, then the command line's overrides: --print-config shows what a run uses.
  ParamNode config = opt.config_path.empty() ? ParamNode::empty() : ParamNode::from_file(opt.config_path);
  if (!opt.law.empty()) config.set_override("rcp.law", opt.law, "--law");
  if (!opt.frequency.empty()) config.set_override("pattern.frequency_hz", opt.frequency, "--frequency-hz");
  load(config, cp);  // validates the overrides too
  config.check_no_unknown_keys();

  ParamNode scenario = opt.scenario_path.empty() ? ParamNode::empty("<no --scenario>") : ParamNode::from_file(opt.scenario_path);
  if (!opt.noise.empty()) scenario.set_override("plant.noise_sigma", opt.noise, "--noise");
  if (app.count("--cycles")) scenario.set_override("run.cycles", std::to_string(opt.cycles), "--cycles");
  if (app.count("--warmup")) scenario.set_override("run.warmup_cycles", std::to_string(opt.warmup), "--warmup");
  if (app.count("--seed")) scenario.set_override("run.seed", std::to_string(opt.seed), "--seed");
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
      if (w < 0 || w >= kNumWhiskers) throw ParamError(opt.scenario_path + ": 'obstacles.whiskers' index " + std::to_string(w) + " is not 0..23");
      spec.obstacles[w] = o;
    }
  }
  scenario.check_no_unknown_keys();

  // The obstacle the flags describe: on every whisker without a scenario, else on --whiskers.
  Obstacle flag_obstacle;
  flag_obstacle.contact_angle = deg_to_rad(10.0);
  const bool flag_obstacles =
      opt.scenario_path.empty() || !opt.whiskers_text.empty() || opt.contact_angle_deg || opt.radial_distance || opt.stiffness;
  std::string flags_dump;
  if (flag_obstacles) {
    if (opt.contact_angle_deg) flag_obstacle.contact_angle = deg_to_rad(*opt.contact_angle_deg);
    if (opt.radial_distance) flag_obstacle.radial_distance = *opt.radial_distance;
    if (opt.stiffness) flag_obstacle.stiffness_scale = *opt.stiffness;
    const std::string whiskers = opt.whiskers_text.empty() ? "all" : opt.whiskers_text;
    for (int w : parse_whiskers(whiskers)) spec.obstacles[w] = flag_obstacle;
    std::ostringstream line;
    line << "flag obstacle: whiskers " << whiskers << ", contact_angle_deg " << rad_to_deg(flag_obstacle.contact_angle)
         << ", radial_distance " << flag_obstacle.radial_distance << ", stiffness_scale "
         << flag_obstacle.stiffness_scale << "\n";
    flags_dump = line.str();
  }
  if (spec.cycles <= spec.warmup_cycles) throw cli::UsageError("--cycles must exceed --warmup");
  spec.compare_without_rcp = !opt.no_compare;
  const std::string dump = config.dump() + scenario.dump() + flags_dump;
  if (opt.print_config) {
    std::cout << dump;
    return 0;
  }
  if (opt.print_params) std::cerr << dump;

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
}

}  // namespace whiskeye::rcp
