// rcp-plant's options (see rcp_plant_app.h).
#include "rcp_plant_app.h"

#include <CLI/CLI.hpp>

namespace whiskeye::rcp {

void add_rcp_plant_options(cli::Program& program, RcpPlantOptions& o) {
  CLI::App& app = program.app();
  program.add_config(o.config_path, "controller parameters YAML (sections pattern, detector, rcp; e.g. config/rcp.yaml)");
  app.add_option("--scenario", o.scenario_path,
                 "scenario YAML: sections plant (PlantParams), run (cycles, warmup_cycles, seed), list obstacles "
                 "(whiskers, contact_angle_deg, radial_distance, stiffness_scale, deflection_direction_deg)")
      ->check(CLI::ExistingFile);
  app.add_option("--cycles", o.cycles, "whisk cycles to run, overrides run.cycles (default 20)")->check(CLI::Range(2, 100000));
  app.add_option("--warmup", o.warmup, "first cycles left out of the figures, overrides run.warmup_cycles (default 1)")
      ->check(CLI::Range(0, 1000));
  app.add_option("--seed", o.seed, "plant noise seed, overrides run.seed (default 1)");
  app.add_option("--whiskers", o.whiskers_text, "whiskers with the flag obstacle: 'all' or e.g. 0,6,12 (default all)");
  app.add_option("--contact-angle-deg", o.contact_angle_deg, "obstacle: protraction angle of first touch, deg (default 10)");
  app.add_option("--radial-distance", o.radial_distance, "obstacle: radial contact distance from the base, m (default 0.05)");
  app.add_option("--stiffness", o.stiffness, "obstacle: stiffness scale (default 1)");
  app.add_option("--law", o.law, "overrides rcp.law")->check(CLI::IsMember({"whiskeye", "rate_limited", "off"}));
  app.add_option("--noise", o.noise, "overrides plant.noise_sigma (Hall x/y, calibrated units)");
  app.add_option("--frequency-hz", o.frequency, "overrides pattern.frequency_hz");
  app.add_flag("--no-compare", o.no_compare, "skip the run without RCP");
  program.add_print_config(o.print_config);
  app.add_flag("--print-params", o.print_params, "print every parameter in use to stderr, then run");
}

}  // namespace whiskeye::rcp
