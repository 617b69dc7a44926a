// The watchdog check of tests/deploy/notify_probe.h as a program, for daemons that can only run in the
// VM (whiskerd needs a CAN interface):
//   watchdog_vm_check [--watchdog-usec N] [--stall-after S] -- DAEMON ARGS...
// Prints the measurements; exit 0 only if every property held.
#include <CLI/CLI.hpp>

#include <iostream>

#include "notify_probe.h"

int main(int argc, char** argv) {
  CLI::App app{"watchdog_vm_check: a daemon's READY/WATCHDOG keep-alives and their stop when its loop stalls"};
  whiskeye::deploy_testing::WatchdogCheck check;
  std::vector<std::string> command;
  app.add_option("--watchdog-usec", check.watchdog_usec, "WATCHDOG_USEC given to the daemon")->check(CLI::Range(100000, 60000000));
  app.add_option("--stall-after", check.stall_after_s, "seconds before the injected stall")->check(CLI::PositiveNumber);
  app.add_option("--window", check.window_s, "seconds of regular keep-alives measured after READY=1")->check(CLI::PositiveNumber);
  app.add_option("--max-gap-factor", check.max_gap_factor, "largest allowed gap, in WATCHDOG_USEC")->check(CLI::PositiveNumber);
  app.add_option("command", command, "the daemon and its arguments (after --)")->required();
  CLI11_PARSE(app, argc, argv);
  const auto r = whiskeye::deploy_testing::check_watchdog(command, check);
  std::cout << r.summary() << "\n--- daemon output ---\n" << r.output << "\n";
  return r.ready && r.problems.empty() ? 0 : 1;
}
