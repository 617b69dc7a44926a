// vita-sim: a simulated WhiskEye in a YAML world, written as an LCM log with the drivers' channels
// (WHISKER_SAMPLE, RCP_STATE, WHISK_CYCLE, CAMERA, ODOMETRY) plus GROUND_TRUTH, SIM_CONTACT_TRUTH and
// SIM_FAULT (the world's injected sensor faults beginning and ending).
// Also draws a world's top-down map (--plot-world), can save camera frames as PNG (--frames-dir), and
// writes the whisker boards' CAN traffic for the same samples as a `candump -l` log (--candump) for
// can-utils' canplayer, using whiskerd's config for the bus mode, ids and (inverted) calibration.
#include "whiskeye/common/bus.h"
#include "whiskeye/common/cli.h"
#include "whiskeye/common/config_path.h"
#include "whiskeye/figure/png_file.h"
#include "whiskeye/sim/can_log.h"
#include "whiskeye/sim/lcm_sink.h"
#include "whiskeye/sim/bringup_cli.h"
#include "whiskeye/sim/generate_cli.h"
#include "whiskeye/sim/simulator.h"
#include "whiskeye/sim/world_plots.h"
#include "whiskeye/whiskerd/config.h"

#include <whiskeye/rcp/params.h>

#include <CLI/CLI.hpp>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <memory>
#include <string>

namespace {

using namespace whiskeye;
using namespace whiskeye::sim;

// One line per injected fault: what, when (s since the start) and what it touched.
std::string fault_summary(const FaultRecord& f, int64_t start_utime) {
  char line[200];
  const auto at = [&](int64_t utime) { return static_cast<double>(utime - start_utime) * 1e-6; };
  std::string what = std::string("fault ") + to_string(f.kind);
  if (f.kind == FaultKind::DeadWhisker) what += " whisker " + std::to_string(f.index);
  if (f.kind == FaultKind::BoardOffline) what += " board " + std::to_string(f.index);
  if (f.kind == FaultKind::OdometrySlip) {
    std::snprintf(line, sizeof line, " x%g", f.value);
    what += line;
  }
  if (f.kind == FaultKind::Kidnap) {
    std::snprintf(line, sizeof line, " to polar angle %.1f deg", rad_to_deg(f.value));
    what += line;
  }
  if (f.began_utime < 0) return what + ": not reached (the run ended first)";
  if (f.kind == FaultKind::Kidnap) {
    std::snprintf(line, sizeof line, ": at %.3f s, put down at x %.3f m, y %.3f m, heading %.1f deg", at(f.began_utime),
                  f.pose.x, f.pose.y, rad_to_deg(f.pose.theta));
    return what + line;
  }
  if (f.ended_utime >= 0) {
    std::snprintf(line, sizeof line, ": %.3f s to %.3f s, ", at(f.began_utime), at(f.ended_utime));
  } else if (f.kind == FaultKind::DeadWhisker) {
    std::snprintf(line, sizeof line, ": the whole run, ");
  } else {
    std::snprintf(line, sizeof line, ": %.3f s to the end of the run, ", at(f.began_utime));
  }
  what += line;
  const std::string n = std::to_string(f.affected);
  switch (f.kind) {
    case FaultKind::DeadWhisker: return what + n + " samples flagged STATUS_FAULT";
    case FaultKind::BoardOffline: return what + n + " board samples stale (4 whiskers STATUS_STALE)";
    case FaultKind::CameraBlackout: return what + n + " camera frames withheld";
    case FaultKind::CameraFreeze: return what + n + " camera frames repeated";
    case FaultKind::OdometrySlip: return what + n + " odometry samples scaled";
    case FaultKind::Kidnap: break;
  }
  return what;
}

// The latest first sample: a run of kMaxLaps slow laps after it still fits an int64 of microseconds.
constexpr int64_t kMaxStartUtime = 4'000'000'000'000'000'000;

// The end of the help of each option whose config has a default (common/config_path.h).
const std::string kDefaultConfigDirs =
    " in the installed config directory, <prefix>/etc/whiskeye or /etc/whiskeye; from a build tree also the "
    "source tree's config/)";

}  // namespace

int main(int argc, char** argv) {
  cli::Program program("vita-sim",
                       "vita-sim: simulated WhiskEye in a YAML world -> LCM log (drivers' channels + GROUND_TRUTH)");
  CLI::App& app = program.app();
  std::string world_path;
  std::string output;
  // The three configs given by no option are found by default_config_path (common/config_path.h).
  std::string robot_path;
  std::string rcp_path;
  std::string plot_path;
  std::string frames_dir;
  std::string views_path;
  std::vector<double> view_angles{90.0, 270.0, 0.0, 180.0};
  int frames_every = 1;
  uint64_t seed = 1;
  double duration = 0.0;
  int64_t laps = 0;  // wide, so that an absurd count reaches the range check below
  int64_t start_utime = SimParams{}.start_utime;
  double start_phase = 0.0;
  bool quiet = false;
  std::string candump_path;
  std::string whiskerd_config;
  std::string can_mode;
  std::string can_interface;
  app.add_option("--world", world_path, "World YAML file (e.g. config/worlds/aliased_arena.yaml)")->check(CLI::ExistingFile);
  GenerateCliOptions generate;
  add_generate_options(app, generate, kDefaultConfigDirs);
  program.add_output(output, "LCM log to write");
  app.add_option("--candump", candump_path,
                 "Also (or only) write the whisker boards' CAN frames as a candump -l log, for canplayer");
  app.add_option("--whiskerd-config", whiskerd_config,
                 "whiskerd YAML giving --candump its bus mode, rate, ids and calibration (inverted; default: "
                 "whiskerd.yaml" +
                     kDefaultConfigDirs);
  app.add_option("--can-mode", can_mode, "--candump bus mode, overrides the whiskerd config's can.mode")
      ->check(CLI::IsMember({"fd", "classic"}));
  app.add_option("--can-interface", can_interface,
                 "Interface name in the --candump log (default: the whiskerd config's can.interface)");
  app.add_option("--robot", robot_path, "Robot geometry YAML (default: robot.yaml" + kDefaultConfigDirs);
  app.add_option("--rcp", rcp_path, "Whisking controller YAML (e.g. config/rcp.yaml; default: built-in defaults)")
      ->check(CLI::ExistingFile);
  app.add_option("--seed", seed, "Seed of every noise source (same seed -> byte-identical log)")->capture_default_str();
  // Bounded below, after the world is loaded (--duration by the world's lap time).
  app.add_option("--duration", duration, "Simulated seconds (overrides --laps; at most " + std::to_string(kMaxLaps) +
                                             " laps' time)");
  app.add_option("--laps", laps, "Revolutions, 1.." + std::to_string(kMaxLaps) + " (default: the world's trajectory.laps)");
  app.add_option("--start-utime", start_utime,
                 "utime of the first sample, 0.." + std::to_string(kMaxStartUtime) +
                     " (a second session on a saved map: after the first session's last)")
      ->capture_default_str();
  app.add_option("--start-phase", start_phase,
                 "Polar angle (rad, -2pi..2pi) of the path the run starts at; overrides the world's "
                 "trajectory.start_angle_deg (a second session from another place)");
  app.add_option("--plot-world", plot_path, "Write a top-down PNG of the world (alone: no simulation)");
  app.add_option("--plot-views", views_path, "Write noise-free camera views at --view-angles as one PNG (alone: no simulation)");
  app.add_option("--view-angles", view_angles, "Polar angles (deg) of the trajectory for --plot-views")
      ->delimiter(',')
      ->capture_default_str();
  app.add_option("--frames-dir", frames_dir, "Also save camera frames as PNG in this directory");
  app.add_option("--frames-every", frames_every, "Save every N-th camera frame")->check(CLI::PositiveNumber);
  std::string camera_format;
  int jpeg_quality = 0;
  app.add_option("--camera-format", camera_format,
                 "CAMERA frames as yuyv, grey or mjpeg (JPEG as a UVC camera sends it, about a twentieth of YUYV's bytes); "
                 "overrides the world's camera.format")
      ->transform(CLI::IsMember({"yuyv", "grey", "mjpeg"}, CLI::ignore_case));
  app.add_option("--jpeg-quality", jpeg_quality,
                 "Quality 1..100 of --camera-format mjpeg's JPEGs; overrides the world's camera.jpeg_quality (default 85)")
      ->check(CLI::Range(1, 100));
  BringupOptions bringup;
  add_bringup_options(app, bringup);
  app.add_flag("--quiet,-q", quiet, "No progress output");
  // A ParamError (a config or world that is missing or wrong): exit 2; any other failure: exit 1.
  return program.run(argc, argv, [&] {
    RobotGeometry robot = default_robot_geometry();
    {
      if (robot_path.empty()) robot_path = default_config_path("robot.yaml", "--robot");
      const ParamNode root = ParamNode::from_file(robot_path);
      load(root.section("robot"), robot);
      root.check_no_unknown_keys();
    }
    // Read where it is used: the simulation, and the generator's whisk period.
    const auto load_controller = [&] {
      rcp::ControllerParams controller;
      if (!rcp_path.empty()) {
        const ParamNode root = ParamNode::from_file(rcp_path);
        rcp::load(root, controller);
        root.check_no_unknown_keys();
      }
      return controller;
    };
    if (generate.generate) return run_generate(generate, robot, load_controller(), quiet);
    if (!bringup.session.empty()) return run_bringup(bringup, candump_path, whiskerd_config, can_interface, seed, start_utime);
    if (world_path.empty()) {
      std::cerr << "vita-sim: --world FILE is required (or --generate-world)\n";
      return 2;
    }
    World world = load_world_file(world_path);
    // The world file's bounds, so that no option runs longer than a world file could.
    if (app.count("--laps") > 0 && !(laps >= 1 && laps <= kMaxLaps)) {
      std::cerr << "vita-sim: --laps " << laps << " is out of range [1, " << kMaxLaps << "]\n";
      return 2;
    }
    const double max_duration = kMaxLaps * world.trajectory.lap_time();
    if (app.count("--duration") > 0 && !(duration > 0.0 && duration <= max_duration)) {
      std::cerr << "vita-sim: --duration " << duration << " is out of range (0, " << max_duration << "] s (" << kMaxLaps
                << " laps of this world)\n";
      return 2;
    }
    if (laps > 0) world.trajectory.laps = static_cast<int>(laps);
    if (!camera_format.empty()) {
      world.camera.format = camera_format == "yuyv"   ? CameraFormat::Yuyv
                            : camera_format == "grey" ? CameraFormat::Grey
                                                      : CameraFormat::Mjpeg;
    }
    if (jpeg_quality > 0) world.camera.jpeg_quality = jpeg_quality;
    if (app.count("--start-phase") > 0) {
      if (!(std::abs(start_phase) <= kTwoPi)) {
        std::cerr << "vita-sim: --start-phase " << start_phase << " is out of range [-2pi, 2pi] rad\n";
        return 2;
      }
      world.trajectory.start_angle = start_phase;
    }
    if (!(start_utime >= 0 && start_utime <= kMaxStartUtime)) {
      std::cerr << "vita-sim: --start-utime " << start_utime << " is out of range [0, " << kMaxStartUtime << "]\n";
      return 2;
    }
    if (!plot_path.empty()) {
      plot_world(world, robot, plot_path);
      std::cerr << "vita-sim: wrote " << plot_path << "\n";
    }
    if (!views_path.empty()) {
      plot_views(world, robot, view_angles, views_path);
      std::cerr << "vita-sim: wrote " << views_path << "\n";
    }
    if (output.empty() && candump_path.empty() && !(plot_path.empty() && views_path.empty())) return 0;
    if (output.empty() && candump_path.empty()) {
      std::cerr << "vita-sim: --output or --candump is required (or --plot-world alone)\n";
      return 2;
    }
    // The boards' traffic as whiskerd is configured to receive it.
    BoardTrafficParams traffic;
    if (!candump_path.empty()) {
      whiskerd::Params wd;
      if (whiskerd_config.empty()) whiskerd_config = default_config_path("whiskerd.yaml", "--whiskerd-config");
      {
        const ParamNode root = ParamNode::from_file(whiskerd_config);
        whiskerd::load(root, wd);
      }
      const wp::BusMode mode = can_mode.empty() ? wd.mode : can_mode == "fd" ? wp::BusMode::kFd : wp::BusMode::kClassic;
      // Another mode than the config's runs at that mode's documented rate (FD 500 Hz, classic 100 Hz).
      traffic.rate_hz = mode == wd.mode ? wd.rate_hz : mode == wp::BusMode::kFd ? 500.0 : 100.0;
      traffic.mode = mode;
      traffic.ids = wd.ids;
      traffic.calibration = wd.calibration;
      if (can_interface.empty()) can_interface = wd.interface;
      const double sim_rate_hz = 1e6 / static_cast<double>(SimParams{}.period_us);
      if (traffic.rate_hz > sim_rate_hz) {
        std::cerr << "vita-sim: the board rate " << traffic.rate_hz << " Hz (" << whiskerd_config
                  << ") exceeds the simulator's " << sim_rate_hz << " Hz\n";
        return 2;
      }
    }
    if (!frames_dir.empty()) std::filesystem::create_directories(frames_dir);

    SimParams params;
    params.seed = seed;
    params.duration = duration;
    params.start_utime = start_utime;
    const rcp::ControllerParams controller = load_controller();
    const rcp::PlantParams plant;
    Simulator sim(world, robot, controller, plant, params);

    std::unique_ptr<LogWriterBus> bus;
    std::unique_ptr<LcmSink> lcm;
    if (!output.empty()) {
      bus = std::make_unique<LogWriterBus>(output);
      lcm = std::make_unique<LcmSink>(*bus, [b = bus.get()](int64_t t) { b->set_time(t); }, world.camera,
                                      plant.saturation);
    }
    std::ofstream candump_file;
    std::unique_ptr<CandumpWriter> candump;
    if (!candump_path.empty()) {
      candump_file.open(candump_path, std::ios::binary | std::ios::trunc);
      if (!candump_file) throw std::runtime_error(candump_path + ": cannot write the candump log");
      candump = std::make_unique<CandumpWriter>(candump_file, traffic, can_interface);
    }
    // The side channels (CAN frames, PNG frames): a thin sink that forwards everything to the LCM
    // sink, if any.
    struct FrameTap : SimSink {
      SimSink* next;
      CandumpWriter* can;
      std::string dir;
      int every;
      FrameTap(SimSink* n, CandumpWriter* c, std::string d, int e) : next(n), can(c), dir(std::move(d)), every(e) {}
      void whisker_sample(const rcp::WhiskerSample& s, const WhiskerHealth& h) override {
        if (next) next->whisker_sample(s, h);
        if (can) can->whisker_sample(s, h);
      }
      void rcp_state(const rcp::ControlOutput& o) override {
        if (next) next->rcp_state(o);
      }
      void whisk_cycle(const rcp::WhiskCycle& c) override {
        if (next) next->whisk_cycle(c);
      }
      void contact_truth(const ContactTruth& t) override {
        if (next) next->contact_truth(t);
      }
      void odometry(int64_t u, int64_t s, const OdometrySample& o) override {
        if (next) next->odometry(u, s, o);
      }
      void ground_truth(int64_t u, const Pose2& p) override {
        if (next) next->ground_truth(u, p);
      }
      void fault(const FaultEvent& e) override {
        if (next) next->fault(e);
      }
      void camera(int64_t u, int64_t s, const std::vector<uint8_t>& g, int w, int h) override {
        if (next) next->camera(u, s, g, w, h);
        if (dir.empty() || s % every != 0) return;
        char name[64];
        std::snprintf(name, sizeof name, "/frame_%06lld.png", static_cast<long long>(s));
        figure::write_png(dir + name, g.data(), w, h, 1, static_cast<std::size_t>(w));
      }
    } tap(lcm.get(), candump.get(), frames_dir, frames_every);

    const bool tty = isatty(STDERR_FILENO) != 0;
    const int64_t total = sim.total_steps();
    int last_shown = -1;
    while (sim.step(tap)) {
      if (quiet) continue;
      if (tty) {
        const int permille = static_cast<int>(1000 * sim.steps_done() / total);
        if (permille != last_shown) {
          last_shown = permille;
          const int bar = permille * 40 / 1000;
          std::fprintf(stderr, "\rvita-sim [%.*s%*s] %5.1f%%", bar, "########################################",
                       40 - bar, "", permille / 10.0);
        }
      } else {
        const int decile = static_cast<int>(10 * sim.steps_done() / total);
        if (decile != last_shown) {
          last_shown = decile;
          std::fprintf(stderr, "vita-sim: %d%%\n", decile * 10);
        }
      }
    }
    if (!quiet && tty) std::fprintf(stderr, "\n");
    std::cerr << "vita-sim: " << sim.duration() << " s simulated\n";
    if (bus) {
      std::cerr << "  " << bus->events_written() << " events -> " << output << "\n";
      for (const auto& [channel, n] : lcm->counts()) std::cerr << "  " << channel << ": " << n << "\n";
    }
    if (candump) {
      candump_file.flush();
      if (!candump_file) throw std::runtime_error(candump_path + ": write failed");
      std::cerr << "  " << candump->frames_written() << " CAN frames (" << candump->samples_sent() << " board samples, "
                << (traffic.mode == wp::BusMode::kFd ? "CAN FD" : "classic CAN") << " at " << traffic.rate_hz
                << " Hz) -> " << candump_path << "\n";
    }
    std::cerr << "  whisk cycles with a true contact: " << sim.cycles_with_contact() << " of " << sim.cycles() << "\n";
    for (std::size_t i = 0; i < world.solids.size(); ++i) {
      std::cerr << "  contact onsets on " << world.solids[i].name << ": " << sim.onsets_per_solid()[i] << "\n";
    }
    for (const FaultRecord& f : sim.faults()) std::cerr << "  " << fault_summary(f, params.start_utime) << "\n";
    return 0;
  });
}
