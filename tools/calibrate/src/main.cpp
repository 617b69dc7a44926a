// whiskeye-calibrate: the first day with a real WhiskEye (docs/bring-up.md). Subcommands bus, rest,
// map, gain and theta, each over the CAN bus (motors off) or a recorded `candump -l` log (--input);
// the estimating ones write a whiskerd calibration drop-in (-o). This file only defines the command
// line; the subcommands are in commands.cpp.
#include <CLI/CLI.hpp>

#include <whiskeye/common/cli.h>

#include "whiskeye/calibrate/commands.h"

int main(int argc, char** argv) {
  using namespace whiskeye;
  cli::Program program("whiskeye-calibrate",
                       "whiskeye-calibrate: bring-up of a WhiskEye's whiskers: bus check, rest offsets, whisker map, "
                       "jig gains, theta end stops; writes whiskerd calibration drop-ins (docs/bring-up.md)");
  CLI::App& app = program.app();
  app.require_subcommand(1);
  app.fallthrough();
  calibrate::Options o;
  program.add_config(o.config,
                     "whiskerd YAML whose calibration (with its drop-ins whiskerd.d/*.yaml) is in use (default: "
                     "the installed whiskerd.yaml)");
  program.add_output(o.output, "the calibration drop-in to write, e.g. /etc/whiskeye/whiskerd.d/20-rest.yaml "
                               "(default: print it)");
  program.add_print_config(o.print_config);
  app.add_option("--input", o.input, "a candump -l log to analyse instead of the bus")->check(CLI::ExistingFile);
  app.add_option("-i,--interface", o.interface, "CAN interface to listen on (default: whiskerd's can.interface)");
  app.add_option("--seconds", o.seconds, "how long to listen on the bus")->check(CLI::Range(0.5, 3600.0))->capture_default_str();

  CLI::App* bus = app.add_subcommand("bus", "per board: present, sample and heartbeat rates, gaps, faults; error "
                                            "frames and bus load; exit 1 if any check fails");
  CLI::App* rest = app.add_subcommand("rest", "whiskers untouched, motors off: offsets and noise; refuses a silent "
                                              "board or a stuck, saturated or noisy sensor");
  CLI::App* map = app.add_subcommand("map", "push each whisker forward then up: its channel, rotation and axis signs");
  CLI::App* gain = app.add_subcommand("gain", "a jig deflects each whisker forward then up by --deflection: gains "
                                              "and rotation");
  CLI::App* theta = app.add_subcommand("theta", "whiskerd's control loop sweeps against both end stops (or --input: a "
                                                "recorded sweep): theta offset and gain");
  for (CLI::App* sub : {map, gain}) {
    sub->add_option("--expect", o.expect, "whiskers in the order touched, e.g. 0,1,2 (default 0..23)")
        ->delimiter(',')
        ->check(CLI::Range(0, 23));
  }
  gain->add_option("--deflection", o.deflection, "the jig's deflection, in whiskerd's units (full scale 1)")->required();
  theta->add_option("--stop-deg", o.stop_deg, "the end stops at ±this (default: whiskerd's rcp.pattern.theta_limit_deg)")
      ->check(CLI::Range(10.0, 90.0));
  theta->add_option("--sweep-seconds", o.sweep_seconds, "on the bus: how long to sweep (0.1 Hz)")
      ->check(CLI::Range(12.0, 600.0))
      ->capture_default_str();
  theta->add_flag("--no-gpio", o.no_gpio, "on the bus: no motor enable / fault lines (a rig without them)");

  return program.run(argc, argv, [&] {
    if (o.print_config) return calibrate::print_config(o);
    if (bus->parsed()) return calibrate::run_bus(o);
    if (rest->parsed()) return calibrate::run_rest(o);
    if (map->parsed()) return calibrate::run_map(o);
    if (gain->parsed()) return calibrate::run_gain(o);
    return calibrate::run_theta(o);
  });
}
