// What vita-sim runs (see vita_sim_app.h): the mode its options select, and a simulation written to
// an LCM log (the drivers' channels, GROUND_TRUTH, SIM_CONTACT_TRUTH, SIM_FAULT) and/or the whisker
// boards' candump log, with camera frames as PNG files on the side.
#include "whiskeye/sim/vita_sim_app.h"

#include "whiskeye/common/bus.h"
#include "whiskeye/common/config_path.h"
#include "whiskeye/common/output_file.h"
#include "whiskeye/figure/png_file.h"
#include "whiskeye/sim/can_log.h"
#include "whiskeye/sim/lcm_sink.h"
#include "whiskeye/sim/world_plots.h"
#include "whiskeye/whiskerd/config.h"

#include <whiskeye/rcp/params.h>

#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <memory>

namespace whiskeye::sim {

namespace {

RobotGeometry load_robot(std::string& path) {
  RobotGeometry robot = default_robot_geometry();
  if (path.empty()) path = default_config_path("robot.yaml", "--robot");
  const ParamNode root = ParamNode::from_file(path);
  load(root.section("robot"), robot);
  root.check_no_unknown_keys();
  return robot;
}

// Read where it is used: the simulation, and the generator's whisk period.
rcp::ControllerParams load_controller(const std::string& path) {
  rcp::ControllerParams controller;
  if (!path.empty()) {
    const ParamNode root = ParamNode::from_file(path);
    rcp::load(root, controller);
    root.check_no_unknown_keys();
  }
  return controller;
}

// The options that change the loaded world, each within the world file's bounds, so that no option
// runs longer than a world file could. Returns 0, or 2 with one line on stderr.
int apply_world_options(const CLI::App& app, const VitaSimOptions& o, World& world) {
  if (app.count("--laps") > 0 && !(o.laps >= 1 && o.laps <= kMaxLaps)) {
    std::cerr << "vita-sim: --laps " << o.laps << " is out of range [1, " << kMaxLaps << "]\n";
    return 2;
  }
  const double max_duration = kMaxLaps * world.trajectory.lap_time();
  if (app.count("--duration") > 0 && !(o.duration > 0.0 && o.duration <= max_duration)) {
    std::cerr << "vita-sim: --duration " << o.duration << " is out of range (0, " << max_duration << "] s (" << kMaxLaps
              << " laps of this world)\n";
    return 2;
  }
  if (o.laps > 0) world.trajectory.laps = static_cast<int>(o.laps);
  if (!o.camera_format.empty()) {
    world.camera.format = o.camera_format == "yuyv"   ? CameraFormat::Yuyv
                          : o.camera_format == "grey" ? CameraFormat::Grey
                                                      : CameraFormat::Mjpeg;
  }
  if (o.jpeg_quality > 0) world.camera.jpeg_quality = o.jpeg_quality;
  if (app.count("--start-phase") > 0) {
    if (!(std::abs(o.start_phase) <= kTwoPi)) {
      std::cerr << "vita-sim: --start-phase " << o.start_phase << " is out of range [-2pi, 2pi] rad\n";
      return 2;
    }
    world.trajectory.start_angle = o.start_phase;
  }
  if (!(o.start_utime >= 0 && o.start_utime <= kMaxStartUtime)) {
    std::cerr << "vita-sim: --start-utime " << o.start_utime << " is out of range [0, " << kMaxStartUtime << "]\n";
    return 2;
  }
  return 0;
}

// The boards' traffic as whiskerd is configured to receive it (its config, found by run_vita_sim,
// --can-mode over it); fills in the interface where the options left it empty. Returns 0, or 2 with
// one line on stderr.
int board_traffic(VitaSimOptions& o, BoardTrafficParams& traffic) {
  whiskerd::Params wd;
  {
    const ParamNode root = ParamNode::from_file(o.whiskerd_config);
    whiskerd::load(root, wd);
  }
  const wp::BusMode mode = o.can_mode.empty()  ? wd.mode
                           : o.can_mode == "fd" ? wp::BusMode::kFd
                                                : wp::BusMode::kClassic;
  // Another mode than the config's runs at that mode's documented rate (FD 500 Hz, classic 100 Hz).
  traffic.rate_hz = mode == wd.mode ? wd.rate_hz : mode == wp::BusMode::kFd ? 500.0 : 100.0;
  traffic.mode = mode;
  traffic.ids = wd.ids;
  traffic.calibration = wd.calibration;
  if (o.can_interface.empty()) o.can_interface = wd.interface;
  const double sim_rate_hz = 1e6 / static_cast<double>(SimParams{}.period_us);
  if (traffic.rate_hz > sim_rate_hz) {
    std::cerr << "vita-sim: the board rate " << traffic.rate_hz << " Hz (" << o.whiskerd_config
              << ") exceeds the simulator's " << sim_rate_hz << " Hz\n";
    return 2;
  }
  return 0;
}

// The side channels (CAN frames, PNG frames): a thin sink that forwards everything to the LCM sink,
// if any.
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
};

// Steps the simulation to its end; progress on stderr unless `quiet`: a bar on a terminal, a line
// every 10 % elsewhere.
void run_to_end(Simulator& sim, SimSink& sink, bool quiet) {
  const bool tty = isatty(STDERR_FILENO) != 0;
  const int64_t total = sim.total_steps();
  int last_shown = -1;
  while (sim.step(sink)) {
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
}

// The simulation of `world`, written to the LCM log and/or the candump log.
int simulate(VitaSimOptions& o, const World& world, const RobotGeometry& robot) {
  BoardTrafficParams traffic;
  if (!o.candump_path.empty()) {
    if (const int status = board_traffic(o, traffic); status != 0) return status;
  }
  if (!o.frames_dir.empty()) std::filesystem::create_directories(o.frames_dir);

  SimParams params;
  params.seed = o.seed;
  params.duration = o.duration;
  params.start_utime = o.start_utime;
  const rcp::ControllerParams controller = load_controller(o.rcp_path);
  const rcp::PlantParams plant;
  Simulator sim(world, robot, controller, plant, params);

  std::unique_ptr<LogWriterBus> bus;
  std::unique_ptr<LcmSink> lcm;
  if (!o.output.empty()) {
    bus = std::make_unique<LogWriterBus>(o.output);
    lcm = std::make_unique<LcmSink>(*bus, [b = bus.get()](int64_t t) { b->set_time(t); }, world.camera,
                                    plant.saturation);
  }
  std::ofstream candump_file;
  std::unique_ptr<CandumpWriter> candump;
  if (!o.candump_path.empty()) {
    candump_file.open(o.candump_path, std::ios::binary | std::ios::trunc);
    if (!candump_file) throw std::runtime_error(o.candump_path + ": cannot write the candump log");
    candump = std::make_unique<CandumpWriter>(candump_file, traffic, o.can_interface);
  }
  FrameTap tap(lcm.get(), candump.get(), o.frames_dir, o.frames_every);
  run_to_end(sim, tap, o.quiet);

  std::cerr << "vita-sim: " << sim.duration() << " s simulated\n";
  if (bus) {
    std::cerr << "  " << bus->events_written() << " events -> " << o.output << "\n";
    for (const auto& [channel, n] : lcm->counts()) std::cerr << "  " << channel << ": " << n << "\n";
  }
  if (candump) {
    candump_file.flush();
    if (!candump_file) throw std::runtime_error(o.candump_path + ": write failed");
    std::cerr << "  " << candump->frames_written() << " CAN frames (" << candump->samples_sent() << " board samples, "
              << (traffic.mode == wp::BusMode::kFd ? "CAN FD" : "classic CAN") << " at " << traffic.rate_hz
              << " Hz) -> " << o.candump_path << "\n";
  }
  std::cerr << "  whisk cycles with a true contact: " << sim.cycles_with_contact() << " of " << sim.cycles() << "\n";
  for (std::size_t i = 0; i < world.solids.size(); ++i) {
    std::cerr << "  contact onsets on " << world.solids[i].name << ": " << sim.onsets_per_solid()[i] << "\n";
  }
  for (const FaultRecord& f : sim.faults()) std::cerr << "  " << fault_summary(f, params.start_utime) << "\n";
  return 0;
}

// No file vita-sim writes is one it reads (exit 2, before anything is opened: the LCM log and the
// candump are truncated when opened), and the files written atomically can be (a world generated for
// minutes is not lost to a FIFO or a symbolic link at the end).
void check_outputs(const VitaSimOptions& o) {
  const std::vector<cli::InputFile> inputs{{"--world", o.world_path},
                                           {"--robot", o.robot_path},
                                           {"--rcp", o.rcp_path},
                                           {"--whiskerd-config", o.whiskerd_config},
                                           {"--slam-config", o.generate.slam_config}};
  const std::pair<const char*, const std::string*> outputs[] = {
      {"--output", &o.output},
      {"--candump", &o.candump_path},
      {"--plot-world", &o.plot_path},
      {"--plot-views", &o.views_path},
      {"--output-world", &o.generate.output_world},
      {"--output-world-json", &o.generate.output_world_json},
      {"--write-true-calibration", &o.bringup.true_calibration_out}};
  for (const auto& [option, path] : outputs) {
    if (!path->empty()) cli::refuse_output_onto_input(option, *path, inputs);
  }
  for (const auto& [option, path] : {outputs[4], outputs[5], outputs[6]}) {
    if (!path->empty()) cli::refuse_unwritable_output(option, *path);
  }
}

}  // namespace

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

int run_vita_sim(const CLI::App& app, VitaSimOptions& o) {
  const RobotGeometry robot = load_robot(o.robot_path);
  // The default configs each mode reads, found now so that no output is one of them either.
  if (o.whiskerd_config.empty() && (!o.candump_path.empty() || !o.bringup.session.empty())) {
    o.whiskerd_config = default_config_path("whiskerd.yaml", "--whiskerd-config").string();
  }
  if (o.generate.generate && o.generate.slam_config.empty()) {
    o.generate.slam_config = default_config_path("slam.yaml", "--slam-config").string();
  }
  check_outputs(o);
  if (o.generate.generate) return run_generate(o.generate, robot, load_controller(o.rcp_path), o.quiet);
  if (!o.bringup.session.empty()) {
    return run_bringup(o.bringup, o.candump_path, o.whiskerd_config, o.can_interface, o.seed, o.start_utime);
  }
  if (o.world_path.empty()) {
    std::cerr << "vita-sim: --world FILE is required (or --generate-world)\n";
    return 2;
  }
  World world = load_world_file(o.world_path);
  if (const int status = apply_world_options(app, o, world); status != 0) return status;
  if (!o.plot_path.empty()) {
    plot_world(world, robot, o.plot_path);
    std::cerr << "vita-sim: wrote " << o.plot_path << "\n";
  }
  if (!o.views_path.empty()) {
    plot_views(world, robot, o.view_angles, o.views_path);
    std::cerr << "vita-sim: wrote " << o.views_path << "\n";
  }
  if (o.output.empty() && o.candump_path.empty() && !(o.plot_path.empty() && o.views_path.empty())) return 0;
  if (o.output.empty() && o.candump_path.empty()) {
    std::cerr << "vita-sim: --output or --candump is required (or --plot-world alone)\n";
    return 2;
  }
  return simulate(o, world, robot);
}

}  // namespace whiskeye::sim
