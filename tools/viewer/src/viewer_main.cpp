// whiskeye-viewer: a web page of what the robot is doing, served by this daemon. Live, it subscribes to
// the stack's channels over LCM (on the robot, or fed by lcm-logplayer) and pushes what changed to each
// browser by Server-Sent Events; with --log FILE it serves a recorded log with a time slider. Wiring
// only: the HTTP API is ViewerServer, what is shown ViewerState, the log LogTimeline, the options
// viewer_options.h.
// Read-only: it publishes nothing and opens no file but its --log. Exit 2 on a bad command line, 1 when
// it cannot start (LCM, the address, the log).
#include "viewer_options.h"

#include "whiskeye/common/bus.h"
#include "whiskeye/common/channels.h"
#include "whiskeye/common/cli.h"
#include "whiskeye/common/clock.h"
#include "whiskeye/common/service.h"
#include "whiskeye/viewer/viewer_server.h"

#include <csignal>
#include <cstdio>
#include <string>
#include <thread>

namespace {

using namespace whiskeye;
using namespace whiskeye::viewer;

volatile std::sig_atomic_t g_signal = 0;
void on_signal(int sig) { g_signal = sig; }

int fail(const std::string& why) {
  std::fprintf(stderr, "whiskeye-viewer: %s\n", why.c_str());
  return 1;
}

int run(ViewerOptions& o) {
  if (!parse_listen(o.listen, o.server)) throw cli::UsageError("--listen " + o.listen + ": expected ADDR:PORT");
  std::unique_ptr<LogTimeline> timeline;
  if (!o.log.empty()) {
    try {
      timeline = LogTimeline::from_file(o.log);
    } catch (const std::exception& e) {
      return fail(e.what());
    }
    if (!timeline->damage().empty()) std::fprintf(stderr, "whiskeye-viewer: %s\n", timeline->damage().c_str());
    if (timeline->events() == 0) return fail(o.log + ": no message of a channel the viewer shows");
  }
  const bool live = !timeline;
  ViewerServer server(o.server, std::move(timeline), o.log);
  std::unique_ptr<LcmBus> bus;
  if (live) {
    try {
      bus = std::make_unique<LcmBus>(o.lcm_url);
    } catch (const std::exception& e) {
      return fail(e.what());
    }
    for (const char* c : {channels::kVitaMap, channels::kVitaPose, channels::kVitaEvent, channels::kVitaMatch,
                          channels::kDriverStatus, channels::kSlamStatus, channels::kWhiskCycle, channels::kCamera}) {
      bus->subscribe_raw(c, [&server](std::span<const uint8_t> data, const MessageInfo& info) {
        server.apply(info.channel, info.recv_utime, data);
      });
    }
  }
  std::string why;
  if (!server.start(why)) return fail(why);
  std::string urls;
  for (const auto& u : server.urls()) urls += (urls.empty() ? "" : " ") + u;
  std::fprintf(stderr, "whiskeye-viewer: %s, serving %s (at most %zu live clients, %zu updates queued each)\n",
               live ? "live on LCM" : ("log " + o.log).c_str(), urls.c_str(), o.server.max_clients, o.server.queue);

  std::signal(SIGINT, on_signal);
  std::signal(SIGTERM, on_signal);
  ServiceNotifier service("whiskeye-viewer", monotonic_us());
  service.ready();
  int64_t next_update = monotonic_us();
  while (g_signal == 0) {
    if (bus) {
      if (bus->handle_timeout(20) < 0 && g_signal == 0) {
        std::fprintf(stderr, "whiskeye-viewer: LCM receive failed\n");
        break;
      }
    } else {
      std::this_thread::sleep_for(std::chrono::milliseconds(100));
    }
    const int64_t now = monotonic_us();
    service.keep_alive(now);
    if (bus && now >= next_update) {
      next_update = now + int64_t{o.update_ms} * 1000;
      server.publish_changes(now);
    }
  }
  service.stopping();
  server.stop();
  std::fprintf(stderr, "whiskeye-viewer: stopped\n");
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  cli::Program program("whiskeye-viewer",
                       "whiskeye-viewer: a web page of the robot's map, pose, camera, whiskers, events and daemons' "
                       "status, live over LCM or from a recorded log (docs/viewer.md)");
  ViewerOptions o;
  add_viewer_options(program, o);
  return program.run(argc, argv, [&] {
    if (!o.log.empty() && !o.lcm_url.empty()) {
      throw cli::UsageError("--log and --lcm-url exclude each other (a log is read, not received)");
    }
    return run(o);
  });
}
