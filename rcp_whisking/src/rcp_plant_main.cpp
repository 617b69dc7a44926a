// rcp-plant: runs the whisking controller against the whisker plant model for N cycles with an
// obstacle and prints JSON (contact rate, peak base deflection with and without RCP, reaction
// latency, false contacts) — how a user tunes RCP without a robot. See docs/rcp-whisking.md.
// Wiring only: the options and the run are in rcp_plant_app.h.
#include "rcp_plant_app.h"

#include <whiskeye/common/cli.h>

int main(int argc, char** argv) {
  whiskeye::cli::Program program("rcp-plant",
                       "rcp-plant: run the whisking controller (pattern, contact detection, RCP) against the whisker "
                       "plant model with an obstacle and print JSON figures: contact rate, peak base deflection with "
                       "and without RCP, reaction latency, false contacts.");
  whiskeye::rcp::RcpPlantOptions options;
  whiskeye::rcp::add_rcp_plant_options(program, options);
  return program.run(argc, argv, [&] { return whiskeye::rcp::run_rcp_plant(program.app(), options); });
}
