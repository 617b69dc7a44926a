// slamd: the ViTa-SLAM daemon.
//   live:    slamd [--mode M] [-c FILE] [--state-dir DIR]         (LCM in and out)
//   offline: slamd --replay IN.lcmlog -o OUT.lcmlog [--mode M]    (reads the log directly)
// See docs/slamd.md.
#include "checkpoint_store.h"
#include "checkpoint_writer.h"
#include "slam_node.h"

#include "whiskeye/common/bus.h"
#include "whiskeye/common/cli.h"
#include "whiskeye/common/clock.h"
#include "whiskeye/common/log.h"
#include "whiskeye/common/log_throttle.h"
#include "whiskeye/common/params.h"
#include "whiskeye/common/robot_geometry.h"
#include "whiskeye/common/service.h"
#include "whiskeye/common/utime.h"
#include "whiskeye/slam/vita_slam.h"

#include <CLI/CLI.hpp>

#include <atomic>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <iostream>
#include <optional>
#include <unistd.h>
#include <utility>

namespace {

using namespace whiskeye;

std::atomic<bool> g_stop{false};

// Messages LCM may hold for slamd's loop per input: a minute of odometry and whisk cycles at their
// nominal rates (50 Hz, about 1 Hz; ~0.3 MB and ~10 MB), ten seconds of camera frames at 5 fps
// (~30 MB of 640x480 YUYV). A burst beyond them is lost as before, but only a burst that long.
constexpr std::pair<const char*, int> kInputQueues[] = {{"ODOMETRY", 3000}, {"WHISK_CYCLE", 60}, {"CAMERA", 50}};

void on_signal(int) { g_stop = true; }

// Each line with its journal priority (common/log.h): `journalctl -p warning -u slamd` shows the
// rejected inputs, the failed checkpoints and the errors, not the progress.
void log_line(const std::string& line) { log_info("slamd: " + line); }
void warn_line(const std::string& line) { log_warning("slamd: " + line); }
void error_line(const std::string& line) { log_error("slamd: " + line); }

struct Options {
  std::string config;
  std::string robot;
  std::string mode;
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
  bool print_config = false;
};

struct Loaded {
  slam::SlamParams slam;
  slamd::NodeParams node;
  RobotGeometry robot = default_robot_geometry();
  std::string dump;
};

// The parameters in use: the files, then the command line's overrides (--mode), so that
// --print-config shows what a run would use.
Loaded load_config(const Options& o) {
  Loaded l;
  ParamNode root = o.config.empty() ? ParamNode::empty() : ParamNode::from_file(o.config);
  if (!o.mode.empty()) root.set_override("slam.mode", o.mode, "--mode");
  slam::load(root.section("slam"), l.slam);
  slamd::load(root.section("slamd"), l.node);
  root.check_no_unknown_keys();
  ParamNode robot = o.robot.empty() ? ParamNode::empty() : ParamNode::from_file(o.robot);
  load(robot.section("robot"), l.robot);
  robot.check_no_unknown_keys();
  l.dump = root.dump() + robot.dump();
  return l;
}

// A progress bar on stderr: redrawn in place on a terminal, a line every 10 % otherwise.
class Progress {
 public:
  void update(double fraction) {
    const int pct = static_cast<int>(fraction * 100.0);
    if (pct == last_) return;
    if (tty_) {
      const int width = 40;
      const int filled = pct * width / 100;
      std::fprintf(stderr, "\rslamd: replay [%s%s] %3d%%", std::string(static_cast<std::size_t>(filled), '#').c_str(),
                   std::string(static_cast<std::size_t>(width - filled), '.').c_str(), pct);
    } else if (pct / 10 != last_ / 10) {
      std::fprintf(stderr, "slamd: replay %d%%\n", pct);
    }
    last_ = pct;
  }
  void done() {
    if (tty_) std::fprintf(stderr, "\n");
  }

 private:
  bool tty_ = ::isatty(2) != 0;
  int last_ = -1;
};

std::unique_ptr<slam::VitaSlam> make_slam(const Loaded& cfg, const Options& o, slamd::CheckpointStore* store) {
  if (!o.map_file.empty()) {
    // Growing the loaded map writes its checkpoints into the state directory: whatever map is there
    // would be rotated out within --checkpoint-keep cycles. The operator says so with --fresh.
    if (!o.localise && !o.fresh && store != nullptr) {
      if (const auto held = store->list(); !held.empty()) {
        throw std::runtime_error("the state directory " + store->directory() + " holds " +
                                 std::to_string(held.size()) + " checkpoint(s) of a map (newest " + held.back() +
                                 ") that growing --map " + o.map_file +
                                 " would rotate out: move them out of it first, or add --fresh to let them go "
                                 "(or --localise, which writes no checkpoints)");
      }
    }
    const slamd::Checkpoint cp = slamd::read_checkpoint(o.map_file);
    std::unique_ptr<slam::VitaSlam> s;
    try {
      s = std::make_unique<slam::VitaSlam>(slam::VitaSlam::deserialise(cp.payload, cfg.slam, cfg.robot));
    } catch (const std::exception& e) {
      throw std::runtime_error(o.map_file + ": " + e.what());
    }
    if (o.localise) s->set_localise_only(true);
    log_line("loaded map " + o.map_file + " (" + std::to_string(s->map().experiences().size()) + " experiences)" +
             (o.localise ? ", localising without growing it" : ""));
    return s;
  }
  if (store != nullptr) {
    for (const auto& f : store->removed_temp_files()) warn_line("removed " + f + " (an unfinished write)");
  }
  if (store != nullptr && !o.fresh) {
    std::vector<std::string> problems;
    std::unique_ptr<slam::VitaSlam> resumed;
    std::optional<slamd::Checkpoint> cp;
    try {
      cp = store->load_newest(&problems, [&](const slamd::Checkpoint& c) {
        resumed = std::make_unique<slam::VitaSlam>(slam::VitaSlam::deserialise(c.payload, cfg.slam, cfg.robot));
      });
    } catch (const slamd::CheckpointError& e) {
      // Intact but not loadable here: starting a new map would rotate it out. The operator decides.
      throw std::runtime_error(std::string("cannot resume from ") + e.what() + " (to keep that map, move it out of " +
                               store->directory() +
                               " first; then start with --fresh for a new map, whose checkpoints rotate the "
                               "older ones out)");
    }
    for (const auto& p : problems) warn_line("skipped unusable checkpoint " + p);
    if (cp) {
      log_line("resuming from " + cp->path + " (after cycle " + std::to_string(cp->sequence) + ")");
      return resumed;
    }
  }
  return std::make_unique<slam::VitaSlam>(cfg.slam, cfg.robot);
}

int run_replay(const Loaded& cfg, const Options& o) {
  LogReader reader(o.replay_in);
  LogWriterBus out(o.replay_out);
  MemoryBus in;
  DecodeErrors errors;  // logged by the node, rate-limited
  // --localise writes no checkpoints: it needs no state directory (nor its lock).
  std::optional<slamd::CheckpointStore> store;
  if (!o.state_dir.empty() && !o.localise) store.emplace(o.state_dir, o.checkpoint_keep);
  slamd::SlamNode node(in, out, make_slam(cfg, o, store ? &*store : nullptr), cfg.node, errors);
  node.set_logger(warn_line);
  if (o.timing) node.set_latency_clock(monotonic_us);
  int64_t checkpointed_cycles = -1;
  LogThrottle throttle;
  const auto checkpoint = [&] {
    try {
      store->write(static_cast<uint64_t>(node.slam().stats().cycles), node.slam().serialise());
      checkpointed_cycles = node.counters().cycles;
      return true;
    } catch (const std::exception& e) {
      // As live: the replay goes on, and the log is rate-limited.
      if (auto line = throttle.admit("checkpoint", std::string("checkpoint failed: ") + e.what(), monotonic_us())) {
        warn_line(*line);
      }
      return false;
    }
  };
  if (store && o.checkpoint_every > 0) {
    node.set_cycle_hook([&](const slam::CycleResult&) {
      if (node.counters().cycles % o.checkpoint_every == 0) checkpoint();
    });
  }
  Progress progress;
  LogReader::EventView ev;
  int64_t next_status = INT64_MIN;
  int64_t last_utime = INT64_MIN;
  int64_t data_us = 0;  // log time covered, counting only forward steps (a clock stepped back adds none)
  const int64_t t0 = monotonic_us();
  std::string channel;
  while (reader.next(ev)) {
    if (last_utime != INT64_MIN && ev.utime > last_utime) data_us += ev.utime - last_utime;
    last_utime = ev.utime;
    out.set_time(ev.utime);
    in.set_time(ev.utime);
    channel.assign(ev.channel);
    // The simulator's truth, for vita-eval (slamd itself never reads it).
    if (channel == channels::kGroundTruth || channel == channels::kSimContactTruth || channel == channels::kSimFault) {
      out.publish_raw(channel, ev.data);
    }
    in.publish_shared(channel, ev.data, ev.owner);  // views into the mapped log, valid while it is
    // First event, or log time stepped back (a recording across a clock step): 1 s from now.
    if (next_status == INT64_MIN || ev.utime < next_status - kUtimePerSecond) next_status = ev.utime + kUtimePerSecond;
    if (ev.utime >= next_status) {
      node.publish_status(ev.utime);
      next_status += kUtimePerSecond;
    }
    progress.update(reader.progress());
  }
  node.flush();
  // The final state, as live slamd writes it on SIGTERM: the cycles after the last periodic
  // checkpoint (or all of them, with --checkpoint-every 0) are not lost.
  bool final_saved = true;
  if (store && checkpointed_cycles != node.counters().cycles) final_saved = checkpoint();
  if (last_utime == INT64_MIN) last_utime = 0;  // an empty log
  node.publish_status(last_utime);
  progress.done();
  const double wall = static_cast<double>(monotonic_us() - t0) * 1e-6;
  const double data = static_cast<double>(data_us) * 1e-6;
  const auto st = node.status(last_utime);
  std::fprintf(stderr,
               "slamd: replayed %.1f s of data in %.2f s (%.0fx real time): %lld cycles, %d templates, %d experiences, "
               "%lld rejected, %lld undecodable\n",
               data, wall, wall > 0 ? data / wall : 0.0, static_cast<long long>(st.cycles), st.num_templates,
               st.num_experiences, static_cast<long long>(st.validation_errors), static_cast<long long>(st.decode_errors));
  // A damaged log (a corrupt event, a last event cut off): every readable event was replayed and the
  // output is complete; the exit status still says the input was damaged.
  if (reader.damage().damaged()) {
    error_line(reader.damage().summary() + " (every readable event was replayed)");
    return 1;
  }
  return final_saved ? 0 : 1;
}

int run_live(const Loaded& cfg, const Options& o) {
  std::string state_dir = o.state_dir;
  if (state_dir.empty()) {
    const char* sd = std::getenv("STATE_DIRECTORY");  // systemd StateDirectory=
    state_dir = sd ? sd : "/var/lib/slamd";
  }
  // --localise writes no checkpoints: it needs no state directory (nor its lock), so it can run next
  // to the service.
  std::optional<slamd::CheckpointStore> store;
  if (!o.localise) store.emplace(state_dir, o.checkpoint_keep);
  LcmBus bus(o.lcm_url);
  DecodeErrors errors;  // logged by the node, rate-limited
  slamd::SlamNode node(bus, bus, make_slam(cfg, o, store ? &*store : nullptr), cfg.node, errors);
  // LCM keeps at most 30 unhandled messages per subscription and drops the rest without a trace: a
  // burst of input (a sender catching up, a busy cycle) then cost the map odometry and frames that a
  // replay of the same messages had (docs/slamd.md, "Input queues").
  for (const auto& [channel, messages] : kInputQueues) bus.set_queue_capacity(channel, messages);
  node.set_logger(warn_line);
  node.set_latency_clock(monotonic_us);
  // The loop only copies the state out; the checksum and the disk are the writer thread's work.
  slamd::CheckpointWriter writer(
      [&store](uint64_t sequence, std::vector<uint8_t>& payload) {
        slam::VitaSlam::seal(payload);
        store->write(sequence, payload);
      },
      warn_line);
  auto checkpoint = [&] {
    writer.submit(static_cast<uint64_t>(node.slam().stats().cycles), node.slam().serialise_unsealed());
  };
  if (o.checkpoint_every > 0 && !o.localise) {
    node.set_cycle_hook([&](const slam::CycleResult&) {
      if (node.counters().cycles % o.checkpoint_every == 0) checkpoint();
    });
  }
  std::signal(SIGTERM, on_signal);
  std::signal(SIGINT, on_signal);
  ServiceNotifier service("slamd", monotonic_us());
  service.ready("running");
  log_line("running in " + slam::to_string(cfg.slam.mode) + " mode, " +
           (store ? "state in " + state_dir : "localising in " + o.map_file + ", no checkpoints"));
  int64_t next_tick = monotonic_us();
  int64_t receive_drops = 0;
  LogThrottle throttle;
  int exit_code = 0;
  while (!g_stop) {
    if (bus.handle_timeout(100) < 0 && !g_stop) {  // a signal interrupting the wait is not a failure
      error_line("LCM receive failed; saving the state and exiting for systemd to restart slamd");
      exit_code = 1;
      break;
    }
    const int64_t now = monotonic_us();
    if (now >= next_tick) {
      auto st = node.status(now_utime(), now);
      slamd::report_checkpoints(st, writer.counters());  // DEGRADED while they fail
      st.lcm_publish_errors = bus.publish_errors();
      // What LCM drops it does not count; the kernel's receive-buffer overflows it can tell.
      if (const int64_t drops = udp_receive_drops(); drops >= 0) {
        if (drops > receive_drops) {
          if (auto line = throttle.admit("lcm drops",
                                         "LCM: " + std::to_string(drops) + " datagram(s) dropped by the kernel so far "
                                         "(receive buffer full: raise recv_buf_size in the LCM URL and net.core.rmem_max)",
                                         now)) {
            warn_line(*line);
          }
        }
        receive_drops = drops;
        st.lcm_receive_drops = drops;
      }
      publish(bus, cfg.node.channels.status, st);
      next_tick = now + 1'000'000;
    }
    service.keep_alive(now);  // sent when due; the loop wakes at least every 100 ms
    // Test-only (WHISKEYE_FAULT_INJECT): a stuck main loop, to prove the watchdog notices.
    service.stall_if_injected(now, [] { return g_stop.load(); });
  }
  service.stopping();
  node.flush();  // cycles still waiting for a camera frame go into the final state
  const int64_t errors_before_final = writer.counters().errors;
  if (store) checkpoint();
  writer.finish();  // the final state is on disk before slamd exits
  log_line("stopped after " + std::to_string(node.counters().cycles) + " cycles");
  if (writer.counters().errors > errors_before_final) {
    // Logged by the writer; the exit status says so too, for systemd and whoever stopped slamd.
    error_line("the final checkpoint was not written: the state since the last one is lost");
    return 1;
  }
  return exit_code;
}

}  // namespace

int main(int argc, char** argv) {
  cli::Program program("slamd", "slamd: ViTa-SLAM daemon (visuo-tactile SLAM for the WhiskEye robot)");
  CLI::App& app = program.app();
  Options o;
  program.add_config(o.config, "SLAM parameters (YAML: slam:, slamd: sections)");
  app.add_option("--robot", o.robot, "robot geometry (YAML: robot: section)")->check(CLI::ExistingFile);
  app.add_option("--mode", o.mode, "visual | tactile | vita (overrides slam.mode)");
  program.add_lcm_url(o.lcm_url);
  app.add_option("--state-dir", o.state_dir, "checkpoint directory (live default: $STATE_DIRECTORY or /var/lib/slamd)");
  app.add_option("--checkpoint-every", o.checkpoint_every, "checkpoint every N cycles (0: only on exit)")->check(CLI::NonNegativeNumber);
  app.add_option("--checkpoint-keep", o.checkpoint_keep, "checkpoints kept")->check(CLI::PositiveNumber);
  app.add_flag("--fresh", o.fresh, "ignore existing checkpoints (rotated out as new ones are written): a new map, or --map's");
  app.add_option("--map", o.map_file, "start from this saved map (a checkpoint file)")->check(CLI::ExistingFile);
  app.add_flag("--localise", o.localise, "with --map: localise in the map without growing it");
  auto* replay = app.add_option("--replay", o.replay_in, "process this LCM log offline")->check(CLI::ExistingFile);
  program.add_output(o.replay_out, "with --replay: output LCM log")->needs(replay);
  app.add_flag("--timing", o.timing, "with --replay: measure latencies into SLAM_STATUS (output no longer byte-identical)");
  program.add_print_config(o.print_config);
  return program.run(argc, argv, [&] {
    if (o.localise && o.map_file.empty()) throw cli::UsageError("--localise needs --map FILE");
    if (!o.replay_in.empty() && o.replay_out.empty()) throw cli::UsageError("--replay needs --output FILE");
    const Loaded cfg = load_config(o);  // a ParamError (a bad file, a --mode it does not know): exit 2
    if (o.print_config) {
      std::cout << cfg.dump;
      return 0;
    }
    return o.replay_in.empty() ? run_live(cfg, o) : run_replay(cfg, o);
  });
}
