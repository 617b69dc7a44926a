// vita-sim's options (see vita_sim_app.h).
#include "whiskeye/sim/vita_sim_app.h"

#include "whiskeye/sim/world.h"

namespace whiskeye::sim {

namespace {

// The end of the help of each option whose config has a default (common/config_path.h).
const std::string kDefaultConfigDirs =
    " in the installed config directory, <prefix>/etc/whiskeye or /etc/whiskeye; from a build tree also the "
    "source tree's config/)";

}  // namespace

void add_vita_sim_options(cli::Program& program, VitaSimOptions& o) {
  CLI::App& app = program.app();
  app.add_option("--world", o.world_path, "World YAML file (e.g. config/worlds/aliased_arena.yaml)")->check(CLI::ExistingFile);
  add_generate_options(app, o.generate, kDefaultConfigDirs);
  program.add_output(o.output, "LCM log to write");
  app.add_option("--candump", o.candump_path,
                 "Also (or only) write the whisker boards' CAN frames as a candump -l log, for canplayer");
  app.add_option("--whiskerd-config", o.whiskerd_config,
                 "whiskerd YAML giving --candump its bus mode, rate, ids and calibration (inverted; default: "
                 "whiskerd.yaml" +
                     kDefaultConfigDirs);
  app.add_option("--can-mode", o.can_mode, "--candump bus mode, overrides the whiskerd config's can.mode")
      ->check(CLI::IsMember({"fd", "classic"}));
  app.add_option("--can-interface", o.can_interface,
                 "Interface name in the --candump log (default: the whiskerd config's can.interface)");
  app.add_option("--robot", o.robot_path, "Robot geometry YAML (default: robot.yaml" + kDefaultConfigDirs);
  app.add_option("--rcp", o.rcp_path, "Whisking controller YAML (e.g. config/rcp.yaml; default: built-in defaults)")
      ->check(CLI::ExistingFile);
  app.add_option("--seed", o.seed, "Seed of every noise source (same seed -> byte-identical log)")->capture_default_str();
  // Bounded in run_vita_sim, after the world is loaded (--duration by the world's lap time).
  app.add_option("--duration", o.duration, "Simulated seconds (overrides --laps; at most " + std::to_string(kMaxLaps) +
                                               " laps' time)");
  app.add_option("--laps", o.laps, "Revolutions, 1.." + std::to_string(kMaxLaps) + " (default: the world's trajectory.laps)");
  app.add_option("--start-utime", o.start_utime,
                 "utime of the first sample, 0.." + std::to_string(kMaxStartUtime) +
                     " (a second session on a saved map: after the first session's last)")
      ->capture_default_str();
  app.add_option("--start-phase", o.start_phase,
                 "Polar angle (rad, -2pi..2pi) of the path the run starts at; overrides the world's "
                 "trajectory.start_angle_deg (a second session from another place)");
  app.add_option("--plot-world", o.plot_path, "Write a top-down PNG of the world (alone: no simulation)");
  app.add_option("--plot-views", o.views_path, "Write noise-free camera views at --view-angles as one PNG (alone: no simulation)");
  app.add_option("--view-angles", o.view_angles, "Polar angles (deg) of the trajectory for --plot-views")
      ->delimiter(',')
      ->capture_default_str();
  app.add_option("--frames-dir", o.frames_dir, "Also save camera frames as PNG in this directory");
  app.add_option("--frames-every", o.frames_every, "Save every N-th camera frame")->check(CLI::PositiveNumber);
  app.add_option("--camera-format", o.camera_format,
                 "CAMERA frames as yuyv, grey or mjpeg (JPEG as a UVC camera sends it, about a twentieth of YUYV's bytes); "
                 "overrides the world's camera.format")
      ->transform(CLI::IsMember({"yuyv", "grey", "mjpeg"}, CLI::ignore_case));
  app.add_option("--jpeg-quality", o.jpeg_quality,
                 "Quality 1..100 of --camera-format mjpeg's JPEGs; overrides the world's camera.jpeg_quality (default 85)")
      ->check(CLI::Range(1, 100));
  add_bringup_options(app, o.bringup);
  app.add_flag("--quiet,-q", o.quiet, "No progress output");
}

}  // namespace whiskeye::sim
