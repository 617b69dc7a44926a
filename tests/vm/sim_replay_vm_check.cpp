// VM test program for the simulated CAN replay (tests/vm/scenario_sim_replay.sh): listens to the
// WHISKER_SAMPLE and DRIVER_STATUS that whiskerd publishes while canplayer replays vita-sim's candump
// log into vcan, and checks them against the WHISKER_SAMPLE of vita-sim's LCM log of the same run:
// every fresh board sample whiskerd publishes must be one of the simulated samples, in order, within
// one quantisation step of the calibration. A log of the same run with another seed serves as the
// negative control: the comparison must tell them apart. Reports PASS/FAIL lines into the results file.
//   sim_replay_vm_check --sim-log FILE --control-log FILE --config whiskerd.yaml --results FILE [--prefix P]
#include <CLI/CLI.hpp>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <iostream>
#include <map>
#include <string>
#include <vector>

#include <whiskeye/common/bus.h>
#include <whiskeye/common/clock.h>
#include <whiskeye/driver_status_t.hpp>
#include <whiskeye/whisker_sample_t.hpp>

#include "whiskeye/whiskerd/config.h"

#include "vm_report.h"

using namespace whiskeye;

namespace {

constexpr int kBoards = wp::kNumBoards;
constexpr int kPerBoard = wp::kWhiskersPerBoard;

bool board_fresh(const whisker_sample_t& m, int b) {
  for (int k = 0; k < kPerBoard; ++k) {
    if (m.status[b * kPerBoard + k] & whisker_sample_t::STATUS_STALE) return false;
  }
  return true;
}

// whiskerd's calibrated values of board b equal the simulator's within one count of quantisation
// (half a count per sensor axis through the gains and the rotation); clipped Hall values only need
// to be at or beyond full scale in the simulation.
bool board_matches(const whisker_sample_t& wd, const whisker_sample_t& sim, int b,
                   const std::array<wp::WhiskerCalibration, wp::kNumWhiskers>& cal) {
  for (int k = 0; k < kPerBoard; ++k) {
    const int w = b * kPerBoard + k;
    const wp::WhiskerCalibration& c = cal[w];
    if (std::abs(wd.theta[w] - sim.theta[w]) > 0.5 * std::abs(c.theta_gain) + 1e-5) return false;
    if (std::abs(wd.raw_x[w]) >= wp::kHallLimit || std::abs(wd.raw_y[w]) >= wp::kHallLimit) continue;
    const double step = 0.5 * (std::abs(c.gain_x) + std::abs(c.gain_y)) + 1e-5;
    if (std::abs(wd.deflection_x[w] - sim.deflection_x[w]) > step) return false;
    if (std::abs(wd.deflection_y[w] - sim.deflection_y[w]) > step) return false;
  }
  return true;
}

std::vector<whisker_sample_t> read_samples(const std::string& path) {
  std::vector<whisker_sample_t> out;
  LogReader log(path);
  LogEvent e;
  while (log.next(e)) {
    if (e.channel != "WHISKER_SAMPLE") continue;
    whisker_sample_t m;
    if (decode_message(std::span<const uint8_t>(e.data), m)) out.push_back(std::move(m));
  }
  return out;
}

struct Embedding {
  int64_t fresh = 0, unmatched = 0, first = -1, last = -1;
  std::string first_unmatched;
};

// Board b's fresh samples embedded, in order, into the simulated sequence. Greedy earliest matching
// decides whether such an embedding exists.
Embedding embed(const std::vector<whisker_sample_t>& received, const std::vector<whisker_sample_t>& sim, int b,
                const std::array<wp::WhiskerCalibration, wp::kNumWhiskers>& cal) {
  Embedding r;
  std::size_t next = 0;
  for (const whisker_sample_t& m : received) {
    if (m.num_whiskers != wp::kNumWhiskers || !board_fresh(m, b)) continue;
    ++r.fresh;
    std::size_t j = next;
    while (j < sim.size() && !board_matches(m, sim[j], b, cal)) ++j;
    if (j == sim.size()) {
      ++r.unmatched;
      if (r.first_unmatched.empty()) {
        // Where it would fit, ignoring the order: a sample from before the last match means whiskerd
        // published an older sample after a newer one; none at all, a value the run never had.
        std::string fits;
        for (std::size_t k = 0; k < sim.size(); ++k) {
          if (board_matches(m, sim[k], b, cal)) fits += (fits.empty() ? "" : ",") + std::to_string(k);
        }
        r.first_unmatched = "board " + std::to_string(b) + " whiskerd seq " + std::to_string(m.seq) + " theta " +
                            std::to_string(m.theta[b * kPerBoard]) + ", after simulated sample " +
                            std::to_string(static_cast<int64_t>(next) - 1) + "; it fits simulated samples [" +
                            (fits.empty() ? "none" : fits) + "]";
      }
      continue;
    }
    if (r.first < 0) r.first = static_cast<int64_t>(j);
    r.last = static_cast<int64_t>(j);
    next = j + 1;
  }
  return r;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"sim_replay_vm_check: whiskerd's output during a canplayer replay vs vita-sim's log"};
  std::string sim_log, control_log, config, results_path, prefix;
  double idle_s = 2.0, timeout_s = 120.0;
  app.add_option("--sim-log", sim_log, "vita-sim's LCM log of the replayed run")->required();
  app.add_option("--control-log", control_log, "vita-sim's LCM log of the same run with another seed")->required();
  app.add_option("--config", config, "whiskerd YAML used by whiskerd and vita-sim")->required();
  app.add_option("--results", results_path, "results file (PASS/FAIL lines appended)")->required();
  app.add_option("--prefix", prefix, "prefix of the reported test names");
  app.add_option("--idle-s", idle_s, "stop listening this long after the last fresh sample");
  app.add_option("--timeout-s", timeout_s, "stop listening after this long in any case");
  CLI11_PARSE(app, argc, argv);

  vm::Report report(results_path, prefix);

  whiskerd::Params params;
  std::vector<whisker_sample_t> sim, control;
  try {
    whiskerd::load(ParamNode::from_file(config), params);
    sim = read_samples(sim_log);
    control = read_samples(control_log);
  } catch (const std::exception& ex) {
    std::cerr << "sim_replay_vm_check: " << ex.what() << "\n";
    report("inputs_readable", false, ex.what());
    return 1;
  }
  std::cout << "simulated samples: " << sim.size() << std::endl;

  std::vector<whisker_sample_t> received;
  driver_status_t last_status;
  bool have_status = false;
  LcmBus bus;
  DecodeErrors decode_errors;
  subscribe<whisker_sample_t>(
      bus, params.channel_sample, [&](const whisker_sample_t& m) { received.push_back(m); }, decode_errors);
  subscribe<driver_status_t>(
      bus, params.channel_status,
      [&](const driver_status_t& m) {
        last_status = m;
        have_status = true;
      },
      decode_errors);
  std::cout << "listening on " << params.channel_sample << std::endl;
  const int64_t start = monotonic_us();
  int64_t last_fresh = -1;
  while (true) {
    const int64_t now = monotonic_us();
    if (static_cast<double>(now - start) > timeout_s * 1e6) break;
    if (last_fresh >= 0 && static_cast<double>(now - last_fresh) > idle_s * 1e6) break;
    const std::size_t before = received.size();
    bus.handle_timeout(50);
    for (std::size_t i = before; i < received.size(); ++i) {
      for (int b = 0; b < kBoards; ++b) {
        if (board_fresh(received[i], b)) last_fresh = monotonic_us();
      }
    }
  }
  std::cout << "whiskerd samples received: " << received.size() << std::endl;
  {
    // Every sample received, beside the results: what a failure is analysed from.
    std::ofstream csv(results_path + "." + (prefix.empty() ? "fd_" : prefix) + "received.csv");
    csv << "seq,utime,stale_boards,theta_first_whisker_of_each_board\n";
    for (const whisker_sample_t& m : received) {
      csv << m.seq << "," << m.utime << ",";
      for (int b = 0; b < kBoards; ++b) csv << (board_fresh(m, b) ? '.' : 's');
      for (int b = 0; b < kBoards; ++b) csv << "," << m.theta[b * kPerBoard];
      csv << "\n";
    }
  }

  int64_t fresh_total = 0, unmatched_total = 0, control_unmatched = 0;
  std::array<Embedding, kBoards> e;
  std::string first_unmatched;
  for (int b = 0; b < kBoards; ++b) {
    e[b] = embed(received, sim, b, params.calibration);
    fresh_total += e[b].fresh;
    unmatched_total += e[b].unmatched;
    if (first_unmatched.empty()) first_unmatched = e[b].first_unmatched;
    control_unmatched += embed(received, control, b, params.calibration).unmatched;
    std::cout << "board " << b << ": " << e[b].fresh << " fresh samples, matched simulated samples " << e[b].first
              << ".." << e[b].last << std::endl;
  }

  std::cout << "against the other seed's log: " << control_unmatched << " of " << fresh_total << " unmatched"
            << std::endl;
  const int64_t n = static_cast<int64_t>(sim.size());
  report("simulated_log_has_samples", n > 100, std::to_string(n) + " samples");
  // whiskerd consumes the latest sample of each board once per period, so under an emulated CPU (and
  // other load on the host) many samples are overwritten before a period uses them: between a quarter
  // and three quarters were seen. A tenth still compares well over a hundred samples per board.
  const double played = static_cast<double>(n) * params.rate_hz / 500.0;  // the simulator runs at 500 Hz
  bool enough = true;
  for (int b = 0; b < kBoards; ++b) enough = enough && static_cast<double>(e[b].fresh) * 10 >= played;
  report("whiskerd_publishes_fresh_replayed_samples_from_every_board", enough,
         std::to_string(fresh_total) + " fresh board samples for " + std::to_string(n) + " simulated samples");
  report("every_fresh_sample_is_a_simulated_sample_in_order_within_one_count", fresh_total > 0 && unmatched_total == 0,
         std::to_string(unmatched_total) + " of " + std::to_string(fresh_total) + " unmatched, first: " + first_unmatched);
  bool covered = true;
  for (int b = 0; b < kBoards; ++b) covered = covered && e[b].first >= 0 && e[b].first < n / 10 && e[b].last >= n * 9 / 10;
  report("the_replay_covers_the_whole_simulated_run", covered,
         "board 0 matched " + std::to_string(e[0].first) + ".." + std::to_string(e[0].last) + " of " + std::to_string(n));
  // The comparison has teeth: another seed's noise and contacts do not fit whiskerd's output.
  report("a_log_of_another_seed_does_not_match", control.size() == sim.size() && control_unmatched * 2 > fresh_total,
         std::to_string(control_unmatched) + " of " + std::to_string(fresh_total) + " unmatched in the control");
  int64_t rejected = -1, heartbeats = -1;
  if (have_status) {
    rejected = 0;
    for (std::size_t i = 0; i < last_status.counter_names.size(); ++i) {
      const std::string& name = last_status.counter_names[i];
      if (name.rfind("rejected_", 0) == 0) rejected += last_status.counter_values[i];
      if (name == "heartbeats") heartbeats = last_status.counter_values[i];
    }
  }
  report("whiskerd_accepts_every_replayed_frame", rejected == 0 && heartbeats > 0,
         "rejected " + std::to_string(rejected) + ", heartbeats " + std::to_string(heartbeats));
  return report.exit_code();
}
