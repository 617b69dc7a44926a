// vita-sim's bring-up mode (--bringup SESSION): a simulated bring-up session of a robot with a drawn
// true calibration, written as the boards' `candump -l` log (docs/simulator.md, "Bring-up sessions").
// The options and their run, so that vita-sim's main only wires them.
#pragma once

#include <CLI/CLI.hpp>

#include <cstdint>
#include <string>
#include <vector>

namespace whiskeye::sim {

struct BringupOptions {
  std::string session;                // rest | taps | sweep | jig; empty: not in bring-up mode
  uint64_t calibration_seed = 1;      // the true calibration's draw
  std::string true_calibration_out;   // write the true calibration as a whiskerd drop-in here
  std::vector<int> order;             // taps, jig: whiskers in the order touched
  double duration = 5.0;              // rest: seconds
  double jig_deflection = 0.5;
  std::vector<int> stuck;             // rest: stuck sensors
  int silent_board = -1;
  double fault_at = -1.0;             // sweep: a fault on board 0 at this time (s)
};

void add_bringup_options(CLI::App& app, BringupOptions& options);

// Writes the session to `candump_path` through the true calibration, with the bus mode, rate and
// ids of the whiskerd config; the true calibration to options.true_calibration_out if given.
// Returns the exit status; a bad option is a cli::UsageError.
int run_bringup(const BringupOptions& options, const std::string& candump_path, const std::string& whiskerd_config,
                const std::string& can_interface, uint64_t seed, int64_t start_utime);

}  // namespace whiskeye::sim
