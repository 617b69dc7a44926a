// vita-sim: a simulated WhiskEye in a YAML world, written as an LCM log with the drivers' channels
// (WHISKER_SAMPLE, RCP_STATE, WHISK_CYCLE, CAMERA, ODOMETRY) plus GROUND_TRUTH, SIM_CONTACT_TRUTH and
// SIM_FAULT (the world's injected sensor faults beginning and ending).
// Also draws a world's top-down map (--plot-world), can save camera frames as PNG (--frames-dir), and
// writes the whisker boards' CAN traffic for the same samples as a `candump -l` log (--candump) for
// can-utils' canplayer, using whiskerd's config for the bus mode, ids and (inverted) calibration;
// draws worlds (--generate-world) and simulates bring-up sessions (--bringup).
// Wiring only: the options and the modes they select are in vita_sim_app.h.
#include "whiskeye/common/cli.h"
#include "whiskeye/sim/vita_sim_app.h"

int main(int argc, char** argv) {
  whiskeye::cli::Program program("vita-sim",
                                 "vita-sim: simulated WhiskEye in a YAML world -> LCM log (drivers' channels + GROUND_TRUTH)");
  whiskeye::sim::VitaSimOptions options;
  whiskeye::sim::add_vita_sim_options(program, options);
  // A ParamError (a config or world that is missing or wrong): exit 2; any other failure: exit 1.
  return program.run(argc, argv, [&] { return whiskeye::sim::run_vita_sim(program.app(), options); });
}
