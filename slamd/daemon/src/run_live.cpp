// slamd live: LCM in and out, checkpoints through the writer thread, SLAM_STATUS once a second,
// systemd notifications, SIGTERM / SIGINT (run.h).
#include "run.h"

#include "whiskeye/slamd/checkpoint_writer.h"

#include "whiskeye/common/bus.h"
#include "whiskeye/common/clock.h"
#include "whiskeye/common/log_throttle.h"
#include "whiskeye/common/service.h"

#include <atomic>
#include <csignal>
#include <cstdint>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace whiskeye::slamd {
namespace {

std::atomic<bool> g_stop{false};

// Messages LCM may hold for slamd's loop per input, by the configured channel names: a minute of
// odometry and whisk cycles at their nominal rates (50 Hz, about 1 Hz; ~0.3 MB and ~10 MB), ten
// seconds of camera frames at 5 fps (~30 MB of 640x480 YUYV). A longer burst loses its excess.
std::vector<std::pair<std::string, int>> input_queues(const NodeChannels& c) {
  return {{c.odometry, 3000}, {c.cycle, 60}, {c.camera, 50}};
}

void on_signal(int) { g_stop = true; }

}  // namespace

int run_live(const Parameters& cfg, const Options& o) {
  const std::string state_dir = live_state_directory(o.state_dir);
  std::optional<CheckpointStore> store;
  open_store(store, state_dir, o.checkpoint_keep, o.localise);
  LcmBus bus(o.lcm_url);
  DecodeErrors errors;  // logged by the node, rate-limited
  SlamNode node(bus, bus, make_slam(cfg, o, store ? &*store : nullptr), cfg.node, errors);
  // LCM keeps at most 30 unhandled messages per subscription and drops the rest without a trace: a
  // burst of input (a sender catching up, a busy cycle) then cost the map odometry and frames that a
  // replay of the same messages had (docs/slamd.md, "Input queues").
  for (const auto& [channel, messages] : input_queues(cfg.node.channels)) bus.set_queue_capacity(channel, messages);
  node.set_logger(warn_line);
  node.set_latency_clock(monotonic_us);
  // The loop only copies the state out; the checksum and the disk are the writer thread's work.
  CheckpointWriter writer(
      [&store](uint64_t sequence, std::vector<uint8_t>& payload) {
        slam::VitaSlam::seal(payload);
        store->write(sequence, payload);
      },
      warn_line);
  auto checkpoint = [&] {
    writer.submit(static_cast<uint64_t>(node.slam().stats().cycles), node.slam().serialise_unsealed());
  };
  if (store) checkpoint_every(node, o.checkpoint_every, checkpoint);
  std::signal(SIGTERM, on_signal);
  std::signal(SIGINT, on_signal);
  ServiceNotifier service("slamd", monotonic_us());
  service.ready("running");
  info_line("running in " + slam::to_string(cfg.slam.mode) + " mode, " +
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
      report_checkpoints(st, writer.counters());  // DEGRADED while they fail
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
  // What LCM already holds (a burst after a pause, what came while the loop took its last message)
  // goes into the final state too: handled until 50 ms pass without a message, for at most 2 s.
  for (const int64_t until = monotonic_us() + 2'000'000; exit_code == 0 && monotonic_us() < until;) {
    if (bus.handle_timeout(50) <= 0) break;
  }
  node.flush();  // cycles still waiting for a camera frame go into the final state
  if (store) checkpoint();
  const bool final_written = writer.finish();  // the final state is on disk before slamd exits
  info_line("stopped after " + std::to_string(node.counters().cycles) + " cycles");
  if (store && !final_written) {
    // Logged by the writer; the exit status says so too, for systemd and whoever stopped slamd.
    error_line("the final checkpoint was not written: the state since the last one is lost");
    return 1;
  }
  return exit_code;
}


}  // namespace whiskeye::slamd
