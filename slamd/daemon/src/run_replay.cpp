// slamd --replay: the log read directly (LogReader), fed to the SlamNode through a MemoryBus, its
// output written to a log (run.h).
#include "run.h"

#include "whiskeye/common/bus.h"
#include "whiskeye/common/clock.h"
#include "whiskeye/common/log_reader.h"
#include "whiskeye/common/log_throttle.h"
#include "whiskeye/common/message_layout.h"
#include "whiskeye/common/utime.h"

#include <cstdint>
#include <cstdio>
#include <optional>
#include <unistd.h>

namespace whiskeye::slamd {
namespace {

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


}  // namespace

int run_replay(const Parameters& cfg, const Options& o) {
  // Read in order into reused chunks: one pass that keeps few views (the camera frames a cycle may
  // still take), and mapping the log's pages costs more than copying them (LogReader::Access).
  LogReader reader(o.replay_in, LogReader::Access::kStreamed);
  LogWriterBus out(o.replay_out);
  MemoryBus in;
  DecodeErrors errors;  // logged by the node, rate-limited
  std::optional<CheckpointStore> store;
  open_store(store, o.state_dir, o.checkpoint_keep, o.localise);
  std::unique_ptr<slam::VitaSlam> slam = make_slam(cfg, o, store ? &*store : nullptr);
  if (!o.inject_wrong_closures.empty()) {
    slam::WrongClosureParams wrong;
    wrong.kind = *slam::wrong_closure_kind(o.inject_wrong_closures);  // the option admits only the kinds
    wrong.seed = o.inject_seed;
    slam->inject_wrong_closures(wrong);
  }
  SlamNode node(in, out, std::move(slam), cfg.node, errors);
  node.set_logger(warn_line);
  // A camera frame's pixels are read only if a cycle takes the frame (one in five on the arena):
  // its header now, for the checks, the rest on demand.
  reader.defer(cfg.node.channels.camera, kCameraFrameHeaderBytes);
  node.set_pixel_reader([&reader](const std::shared_ptr<const void>& owner, std::span<const uint8_t> wanted) {
    reader.read_rest(owner, wanted);
  });
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
  if (store) checkpoint_every(node, o.checkpoint_every, [&] { checkpoint(); });
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
    in.publish_shared(channel, ev.data, ev.owner);  // views into the log's chunk, valid while it is held
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
  if (!o.inject_wrong_closures.empty()) {
    info_line("injected " + std::to_string(node.slam().wrong_closures_added()) + " wrong closures (" +
              o.inject_wrong_closures + ", seed " + std::to_string(o.inject_seed) + ")");
  }
  // A damaged log (a corrupt event, a last event cut off): every readable event was replayed and the
  // output is complete; the exit status still says the input was damaged.
  if (reader.damage().damaged()) {
    error_line(reader.damage().summary() + " (every readable event was replayed)");
    return 1;
  }
  return final_saved ? 0 : 1;
}

}  // namespace whiskeye::slamd
