// whiskeye-calibrate's subcommands (docs/bring-up.md): where the frames come from (a `candump -l`
// log, or the CAN interface with the motors off), whiskerd's calibration in use (its config and
// drop-ins), the estimators (estimators.h), the table printed and the drop-in written. The tool's
// edge: main.cpp only defines the command line.
#pragma once

#include <string>
#include <vector>

namespace whiskeye::calibrate {

struct Options {
  std::string config;          // whiskerd.yaml (its drop-ins beside it are read too); empty: the default one
  std::string input;           // a candump -l log; empty: listen on the bus
  std::string interface;       // empty: whiskerd's can.interface
  double seconds = 10.0;       // how long to listen on the bus
  std::string output;          // the drop-in to write; empty: print it
  std::vector<int> expect;     // map, gain: whiskers in the order touched (empty: 0..23)
  double deflection = 0.0;     // gain: the jig's deflection (whiskerd's units)
  double stop_deg = 0.0;       // theta: the end stops at ±this (0: whiskerd's rcp.pattern.theta_limit_deg)
  double sweep_seconds = 25.0; // theta on the bus: how long whiskerd sweeps
  bool no_gpio = false;        // theta on the bus: no motor enable / fault lines (a rig without them)
  bool print_config = false;   // print whiskerd's configuration in use (file and drop-ins) and exit
};

// Each returns the exit status: 0 done (and the drop-in written), 1 the input shows a problem (one
// line each on stderr, nothing written). A bad option or config throws (cli::UsageError, ParamError).
// whiskerd's configuration the subcommands take as the calibration in use: its file, then its drop-ins.
int print_config(const Options& options);
int run_bus(const Options& options);
int run_rest(const Options& options);
int run_map(const Options& options);
int run_gain(const Options& options);
int run_theta(const Options& options);

}  // namespace whiskeye::calibrate
