// vita-sim's bring-up mode (see bringup_cli.h).
#include "whiskeye/sim/bringup_cli.h"

#include <whiskeye/common/cli.h>
#include <whiskeye/common/config_path.h>
#include <whiskeye/common/output_file.h>
#include <whiskeye/common/params.h>

#include <fstream>
#include <iostream>
#include <stdexcept>

#include "whiskeye/sim/bringup.h"
#include "whiskeye/sim/can_log.h"
#include "whiskeye/whiskerd/config.h"

namespace whiskeye::sim {

void add_bringup_options(CLI::App& app, BringupOptions& o) {
  app.add_option("--bringup", o.session,
                 "Write a bring-up session of a robot with a drawn true calibration to --candump: rest, taps, sweep "
                 "or jig (docs/bring-up.md)")
      ->check(CLI::IsMember({"rest", "taps", "sweep", "jig"}));
  app.add_option("--true-calibration-seed", o.calibration_seed, "--bringup: seed of the drawn true calibration")
      ->capture_default_str();
  app.add_option("--write-true-calibration", o.true_calibration_out,
                 "--bringup: also write the true calibration as a whiskerd drop-in YAML");
  app.add_option("--bringup-order", o.order, "--bringup taps|jig: the whiskers touched, in order (default 0..23)")
      ->delimiter(',')
      ->check(CLI::Range(0, 23));
  app.add_option("--bringup-duration", o.duration, "--bringup rest: seconds")->check(CLI::Range(0.5, 600.0))->capture_default_str();
  app.add_option("--jig-deflection", o.jig_deflection, "--bringup jig: the jig's deflection (whiskerd's units)")
      ->check(CLI::Range(0.05, 0.95))
      ->capture_default_str();
  app.add_option("--stuck-whiskers", o.stuck, "--bringup: whiskers whose Hall sensor is stuck")->delimiter(',')->check(CLI::Range(0, 23));
  app.add_option("--silent-board", o.silent_board, "--bringup: a board that sends nothing")->check(CLI::Range(0, 5));
  app.add_option("--fault-at", o.fault_at, "--bringup sweep: board 0 reports a fault from this time (s)")
      ->check(CLI::Range(0.0, 600.0));
}

int run_bringup(const BringupOptions& o, const std::string& candump_path, const std::string& whiskerd_config,
                const std::string& can_interface, uint64_t seed, int64_t start_utime) {
  if (candump_path.empty()) throw cli::UsageError("--bringup needs --candump FILE");
  whiskerd::Params wd;
  const std::string config =
      whiskerd_config.empty() ? default_config_path("whiskerd.yaml", "--whiskerd-config").string() : whiskerd_config;
  whiskerd::load(ParamNode::from_file(config), wd);
  const TrueCalibration truth = draw_true_calibration(o.calibration_seed);

  SessionParams sp;
  if (!parse_session(o.session, sp.session)) throw cli::UsageError("--bringup " + o.session + ": unknown session");
  sp.rate_hz = wd.rate_hz;
  sp.start_utime = start_utime;
  sp.seed = seed;
  sp.order = o.order;
  sp.rest_s = o.duration;
  sp.jig_deflection = o.jig_deflection;
  sp.theta_stop = wd.controller.pattern.theta_limit;
  sp.stuck = o.stuck;
  sp.silent_board = o.silent_board;
  sp.fault_at_s = o.fault_at;

  BoardTrafficParams traffic;
  traffic.mode = wd.mode;
  traffic.rate_hz = wd.rate_hz;
  traffic.ids = wd.ids;
  traffic.calibration = truth.calibration;
  traffic.channel = truth.channel;
  std::ofstream out(candump_path, std::ios::binary | std::ios::trunc);
  if (!out) throw std::runtime_error(candump_path + ": cannot write the candump log");
  CandumpWriter writer(out, traffic, can_interface.empty() ? wd.interface : can_interface);
  run_session(sp, [&](const rcp::WhiskerSample& s, const WhiskerHealth& h) { writer.whisker_sample(s, h); });
  out.flush();
  if (!out) throw std::runtime_error(candump_path + ": write failed");
  std::cerr << "vita-sim: bring-up session " << o.session << ": " << writer.frames_written() << " CAN frames -> "
            << candump_path << " (true calibration seed " << o.calibration_seed << ": whiskers " << truth.swapped[0]
            << " and " << truth.swapped[1] << " swapped, board " << truth.mirrored_board << " mirrored)\n";

  if (!o.true_calibration_out.empty()) {
    whiskerd::CoreParams truth_params;
    truth_params.calibration = truth.calibration;
    truth_params.channel = truth.channel;
    std::vector<whiskerd::CalibrationEntry> entries;
    for (int w = 0; w < wp::kNumWhiskers; ++w) entries.push_back({w, whiskerd::calibration_keys(truth_params, w)});
    // A whiskerd drop-in: written as whiskeye-calibrate writes its own.
    write_file_atomically(o.true_calibration_out,
                          whiskerd::format_dropin(entries, "the true calibration vita-sim drew (seed " +
                                                               std::to_string(o.calibration_seed) + ")"));
  }
  return 0;
}

}  // namespace whiskeye::sim
