// slamd's two ways of running, each the wiring of one SlamNode (main.cpp parses the command line and
// picks one): live (run_live.cpp: LCM in and out, checkpoints through the writer thread, systemd
// notifications, signals) and offline (run_replay.cpp: --replay, a log in and a log out through a
// MemoryBus, checkpoints written at once). What map they start from: startup.h.
#pragma once

#include "whiskeye/slamd/checkpoint_store.h"
#include "whiskeye/slamd/slam_node.h"
#include "whiskeye/slamd/startup.h"

#include "whiskeye/common/log.h"
#include "whiskeye/common/robot_geometry.h"
#include "whiskeye/slam/vita_slam.h"

#include <cstdio>
#include <memory>
#include <cstdint>
#include <string>

namespace whiskeye::slamd {

// The command line.
struct Options {
  std::string config;
  std::string robot;
  std::string mode;
  std::vector<std::string> sets;  // --set KEY=VALUE
  std::string lcm_url;
  std::string state_dir;
  int checkpoint_every = 1;
  int checkpoint_keep = 3;
  bool fresh = false;
  std::string map_file;
  bool localise = false;
  std::string replay_in;
  std::string replay_out;
  bool timing = false;
  std::string inject_wrong_closures;  // --inject-wrong-closures KIND (a test of the back end; replay only)
  uint64_t inject_seed = 1;
  bool print_config = false;
};

// The parameters in use: slam.yaml's (the command line's overrides included) and robot.yaml's, with
// their --print-config text.
struct Parameters {
  slam::SlamParams slam;
  NodeParams node;
  RobotGeometry robot = default_robot_geometry();
  std::string dump;
};

// "slamd: <line>" on stderr with its journal priority (common/log.h): `journalctl -p warning -u slamd`
// shows the rejected inputs, the failed checkpoints and the errors, not the progress.
inline void slamd_log(LogLevel level, const std::string& line) { whiskeye::log_line(level, "slamd: " + line); }
inline void info_line(const std::string& line) { slamd_log(LogLevel::kInfo, line); }
inline void warn_line(const std::string& line) { slamd_log(LogLevel::kWarning, line); }
inline void error_line(const std::string& line) { slamd_log(LogLevel::kError, line); }

// The map slamd starts from (whiskeye/slamd/startup.h: --map, resume or --fresh).
inline std::unique_ptr<slam::VitaSlam> make_slam(const Parameters& cfg, const Options& o, CheckpointStore* store) {
  return start_slam(cfg.slam, cfg.robot, StartupOptions{o.map_file, o.localise, o.fresh}, store, slamd_log);
}


// Until SIGTERM / SIGINT, or a failed LCM receive (exit 1); the final state is checkpointed.
int run_live(const Parameters& cfg, const Options& o);
// The whole of --replay's log; 1 if the log was damaged or the final checkpoint failed.
int run_replay(const Parameters& cfg, const Options& o);

}  // namespace whiskeye::slamd
