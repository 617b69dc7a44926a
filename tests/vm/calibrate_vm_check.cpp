// The VM scenario calibrate's verdict: whiskerd's configuration with the drop-ins whiskeye-calibrate
// wrote in the guest (its loader, as whiskerd runs it) against the true calibration vita-sim drew.
// One PASS/FAIL line per check in the results file; exit 0 when it could compare (the lines decide).
//   calibrate_vm_check --truth TRUTH.yaml --config whiskerd.yaml --whiskers 0,5,... --results FILE
#include <CLI/CLI.hpp>

#include <cmath>
#include <fstream>
#include <iostream>
#include <string>
#include <vector>

#include "whiskeye/common/params.h"
#include "whiskeye/whiskerd/config.h"

using namespace whiskeye;

int main(int argc, char** argv) {
  CLI::App app("calibrate_vm_check");
  std::string truth_path, config, results;
  std::vector<int> whiskers;
  app.add_option("--truth", truth_path)->required();
  app.add_option("--config", config)->required();
  app.add_option("--whiskers", whiskers, "the whiskers the taps and the jig touched")->delimiter(',')->required();
  app.add_option("--results", results)->required();
  CLI11_PARSE(app, argc, argv);
  whiskerd::Params loaded;
  whiskerd::CoreParams truth;
  try {
    whiskerd::load_with_dropins(ParamNode::from_file(config), config, loaded);
    whiskerd::load_dropin(ParamNode::from_file(truth_path), truth);
  } catch (const std::exception& e) {
    std::cerr << "calibrate_vm_check: " << e.what() << "\n";
    return 1;
  }
  std::ofstream out(results, std::ios::app);
  // One line per check: the worst whisker and its error.
  auto verdict = [&](const std::string& name, const std::vector<int>& ws, double tolerance, auto error) {
    double worst = 0;
    int worst_w = -1;
    for (int w : ws) {
      const double e = error(w);
      if (!(e <= worst)) {
        worst = e;
        worst_w = w;
      }
    }
    const std::string line = (worst <= tolerance ? "PASS " : "FAIL ") + name +
                             (worst <= tolerance ? "" : ": whisker " + std::to_string(worst_w) + " off by " +
                                                            std::to_string(worst) + ", tolerance " + std::to_string(tolerance));
    out << line << "\n";
    std::cout << line << " (worst " << worst << ")\n";
  };
  std::vector<int> all;
  for (int w = 0; w < kNumWhiskers; ++w) all.push_back(w);
  auto cal = [](const whiskerd::CoreParams& p, int w) -> const wp::WhiskerCalibration& {
    return p.calibration[static_cast<std::size_t>(w)];
  };
  verdict("wiring_is_the_true_one", all, 0.0,
          [&](int w) { return std::abs(loaded.channel[static_cast<std::size_t>(w)] - truth.channel[static_cast<std::size_t>(w)]); });
  verdict("offsets_within_1_count", all, 1.0, [&](int w) {
    return std::max(std::abs(cal(loaded, w).offset_x - cal(truth, w).offset_x),
                    std::abs(cal(loaded, w).offset_y - cal(truth, w).offset_y));
  });
  verdict("gains_within_0.3_percent", whiskers, 0.003, [&](int w) {
    return std::max(std::abs(cal(loaded, w).gain_x / cal(truth, w).gain_x - 1),
                    std::abs(cal(loaded, w).gain_y / cal(truth, w).gain_y - 1));
  });
  verdict("rotations_within_3_mrad", whiskers, 0.003,
          [&](int w) { return std::abs(cal(loaded, w).rotation - cal(truth, w).rotation); });
  verdict("theta_offsets_within_1_count", all, 1.0,
          [&](int w) { return std::abs(cal(loaded, w).theta_offset - cal(truth, w).theta_offset); });
  verdict("theta_gains_within_0.2_percent", all, 0.002,
          [&](int w) { return std::abs(cal(loaded, w).theta_gain / cal(truth, w).theta_gain - 1); });
  return 0;
}
