// whiskeye-viewer: a web page of what the robot is doing, served by this daemon. Live, it subscribes to
// the stack's channels over LCM (on the robot, or fed by lcm-logplayer) and pushes what changed to each
// browser by Server-Sent Events; with --log FILE it serves a recorded log with a time slider. Wiring
// only: what is shown is ViewerState, the clients' queues ClientHub, the log LogTimeline.
// Read-only: it publishes nothing and opens no file but its --log. Exit 2 on a bad command line, 1 when
// it cannot start (LCM, the address, the log).
#include "whiskeye/common/bus.h"
#include "whiskeye/common/channels.h"
#include "whiskeye/common/cli.h"
#include "whiskeye/common/clock.h"
#include "whiskeye/common/service.h"
#include "whiskeye/viewer/assets.h"
#include "whiskeye/viewer/client_hub.h"
#include "whiskeye/viewer/log_timeline.h"
#include "whiskeye/viewer/viewer_state.h"

#include <CLI/CLI.hpp>
#include <httplib.h>

#include <atomic>
#include <csignal>
#include <cstdio>
#include <mutex>
#include <optional>
#include <string>
#include <thread>

namespace {

using namespace whiskeye;
using namespace whiskeye::viewer;
using nlohmann::json;

volatile std::sig_atomic_t g_signal = 0;
void on_signal(int sig) { g_signal = sig; }

struct Options {
  std::string listen = "127.0.0.1:8088";
  std::string lcm_url;
  std::string log;
  std::size_t max_clients = 8;
  std::size_t queue = 64;
  int update_ms = 100;
};

// "ADDR:PORT" → address and port; false when malformed.
bool parse_listen(const std::string& s, std::string& host, int& port) {
  const auto colon = s.rfind(':');
  if (colon == std::string::npos || colon == 0 || colon + 1 == s.size()) return false;
  host = s.substr(0, colon);
  if (host.size() > 2 && host.front() == '[' && host.back() == ']') host = host.substr(1, host.size() - 2);
  try {
    std::size_t used = 0;
    port = std::stoi(s.substr(colon + 1), &used);
    return used == s.size() - colon - 1 && port >= 0 && port <= 65535;
  } catch (const std::exception&) {
    return false;
  }
}

// Headers every answer carries: the page loads nothing from elsewhere and nothing is cached.
void harden(httplib::Response& res) {
  res.set_header("X-Content-Type-Options", "nosniff");
  res.set_header("Content-Security-Policy", "default-src 'self'; img-src 'self'; style-src 'self'; script-src 'self'");
  res.set_header("Cache-Control", "no-store");
  res.set_header("Referrer-Policy", "no-referrer");
}

std::string sse(const char* event, const std::string& data) {
  return std::string("event: ") + event + "\ndata: " + data + "\n\n";
}

class Viewer {
 public:
  explicit Viewer(const Options& o) : o_(o), hub_(o.max_clients, o.queue) {}

  int run() {
    std::string host;
    int port = 0;
    if (!parse_listen(o_.listen, host, port)) return usage("--listen " + o_.listen + ": expected ADDR:PORT");
    if (!o_.log.empty()) {
      try {
        timeline_ = LogTimeline::from_file(o_.log);
      } catch (const std::exception& e) {
        std::fprintf(stderr, "whiskeye-viewer: %s\n", e.what());
        return 1;
      }
      if (!timeline_->damage().empty()) std::fprintf(stderr, "whiskeye-viewer: %s\n", timeline_->damage().c_str());
      if (timeline_->events() == 0) {
        std::fprintf(stderr, "whiskeye-viewer: %s: no message of a channel the viewer shows\n", o_.log.c_str());
        return 1;
      }
    }
    std::unique_ptr<LcmBus> bus;
    if (!timeline_) {
      try {
        bus = std::make_unique<LcmBus>(o_.lcm_url);
      } catch (const std::exception& e) {
        std::fprintf(stderr, "whiskeye-viewer: %s\n", e.what());
        return 1;
      }
      for (const char* c : {channels::kVitaMap, channels::kVitaPose, channels::kVitaEvent, channels::kVitaMatch,
                            channels::kDriverStatus, channels::kSlamStatus, channels::kWhiskCycle, channels::kCamera}) {
        bus->subscribe_raw(c, [this](std::span<const uint8_t> data, const MessageInfo& info) {
          std::lock_guard lock(mutex_);
          state_.apply(info.channel, info.recv_utime, data);
        });
      }
    }

    httplib::Server server;
    // One thread per streaming client, and a few for everything else.
    const std::size_t threads = o_.max_clients + 4;
    server.new_task_queue = [threads] { return new httplib::ThreadPool(threads); };
    server.set_keep_alive_timeout(2);
    server.set_write_timeout(5, 0);
    server.set_payload_max_length(1024);  // it takes no uploads
    routes(server);
    if (port == 0) {
      port = server.bind_to_any_port(host);
      if (port < 0) return cannot_listen(host, 0);
    } else if (!server.bind_to_port(host, port)) {
      return cannot_listen(host, port);
    }
    std::thread http([&] { server.listen_after_bind(); });
    std::fprintf(stderr, "whiskeye-viewer: %s, serving http://%s:%d/ (at most %zu live clients, %zu updates queued each)\n",
                 timeline_ ? ("log " + o_.log).c_str() : "live on LCM", host.c_str(), port, o_.max_clients, o_.queue);

    std::signal(SIGINT, on_signal);
    std::signal(SIGTERM, on_signal);
    ServiceNotifier service("whiskeye-viewer", monotonic_us());
    service.ready();
    ViewerState::Cursor cursor;
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
        next_update = now + int64_t{o_.update_ms} * 1000;
        std::lock_guard lock(mutex_);
        state_.set_now(now_utime());
        // With no page open nothing is built (a page that connects starts from the whole state).
        if (hub_.clients() > 0) {
          json delta = state_.delta(cursor, now);
          if (!delta.empty()) hub_.broadcast(std::make_shared<const std::string>(sse("delta", delta.dump())));
        }
      }
    }
    service.stopping();
    hub_.close_all();
    server.stop();
    http.join();
    std::fprintf(stderr, "whiskeye-viewer: stopped\n");
    return 0;
  }

 private:
  int usage(const std::string& why) {
    std::fprintf(stderr, "whiskeye-viewer: %s\n", why.c_str());
    return 2;
  }
  int cannot_listen(const std::string& host, int port) {
    std::fprintf(stderr, "whiskeye-viewer: cannot listen on %s:%d (address in use or not on this host)\n", host.c_str(), port);
    return 1;
  }

  // The state a request sees: live, the shared one; in a log, the timeline at ?t= (or where it is).
  // Called with mutex_ held.
  const ViewerState& state_for(const httplib::Request& req) {
    if (!timeline_) return state_;
    if (req.has_param("t")) {
      try {
        return timeline_->seek(std::stoll(req.get_param_value("t")));
      } catch (const std::exception&) {
      }
    }
    return timeline_->state();
  }

  json server_json() const {
    const ClientHub::Stats s = hub_.stats();
    json clients = json::array();
    for (const auto& c : s.per_client) clients.push_back({{"id", c.id}, {"sent", c.sent}, {"dropped", c.dropped}, {"resyncs", c.resyncs}});
    json out = {{"mode", timeline_ ? "log" : "live"},
                {"clients", s.clients},
                {"max_clients", s.max_clients},
                {"queue_capacity", s.queue_capacity},
                {"joined", s.joined},
                {"refused", s.refused},
                {"updates", s.broadcasts},
                {"dropped", s.dropped},
                {"per_client", std::move(clients)}};
    if (timeline_) {
      out["log"] = {{"file", o_.log},
                    {"start", timeline_->start_utime()},
                    {"end", timeline_->end_utime()},
                    {"events", timeline_->events()},
                    {"damage", timeline_->damage()}};
    }
    return out;
  }

  void routes(httplib::Server& server) {
    server.Get("/api/snapshot", [this](const httplib::Request& req, httplib::Response& res) {
      harden(res);
      json snap;
      {
        std::lock_guard lock(mutex_);
        snap = state_for(req).snapshot();
      }
      snap["server"] = server_json();
      res.set_content(snap.dump(), "application/json");
    });
    server.Get("/status", [this](const httplib::Request&, httplib::Response& res) {
      harden(res);
      json out = server_json();
      {
        std::lock_guard lock(mutex_);
        const json snap = (timeline_ ? timeline_->state() : state_).snapshot();
        out["meta"] = snap["meta"];
        out["status"] = snap["status"];
        out["num_experiences"] = (timeline_ ? timeline_->state() : state_).num_experiences();
      }
      res.set_content(out.dump(2) + "\n", "application/json");
    });
    server.Get("/api/camera.jpg", [this](const httplib::Request& req, httplib::Response& res) {
      harden(res);
      std::shared_ptr<const std::string> jpeg;
      {
        std::lock_guard lock(mutex_);
        jpeg = state_for(req).camera_jpeg();
      }
      if (!jpeg) {
        res.status = 404;
        res.set_content("no camera frame\n", "text/plain");
        return;
      }
      // The pointer keeps the bytes alive while they are sent, after the lock is released.
      res.set_content_provider(jpeg->size(), "image/jpeg",
                               [jpeg](std::size_t offset, std::size_t length, httplib::DataSink& sink) {
                                 return sink.write(jpeg->data() + offset, length);
                               });
    });
    server.Get("/api/events", [this](const httplib::Request&, httplib::Response& res) {
      harden(res);
      if (timeline_) {
        res.status = 404;
        res.set_content("a log has no live updates: use /api/snapshot?t=\n", "text/plain");
        return;
      }
      std::shared_ptr<ClientQueue> client = hub_.join();
      if (!client) {
        res.status = 503;
        res.set_content("too many viewers (--max-clients)\n", "text/plain");
        return;
      }
      res.set_chunked_content_provider(
          "text/event-stream",
          [this, client](std::size_t, httplib::DataSink& sink) {
            Update update;
            switch (client->pop(update, std::chrono::seconds(2))) {
              case ClientQueue::Next::kResync: {
                json snap;
                {
                  std::lock_guard lock(mutex_);
                  snap = state_.snapshot();
                }
                snap["server"] = server_json();
                const std::string text = sse("snapshot", snap.dump());
                return sink.write(text.data(), text.size());
              }
              case ClientQueue::Next::kUpdate: return sink.write(update->data(), update->size());
              case ClientQueue::Next::kTimeout: {
                // Keeps proxies from closing an idle stream, and finds out whether the client is gone.
                const std::string text = sse("server", server_json().dump());
                return sink.write(text.data(), text.size());
              }
              case ClientQueue::Next::kClosed: break;
            }
            sink.done();
            return false;
          },
          [this, client](bool) { hub_.leave(client); });
    });
    // Everything else is one of the page's own files, by exact name, or nothing.
    server.Get(".*", [](const httplib::Request& req, httplib::Response& res) {
      harden(res);
      const Asset* asset = find_asset(req.path);
      if (!asset) {
        res.status = 404;
        res.set_content("not found\n", "text/plain");
        return;
      }
      res.set_content(asset->body.data(), asset->body.size(), std::string(asset->content_type).c_str());
    });
    server.set_error_handler([](const httplib::Request&, httplib::Response& res) {
      harden(res);
      if (res.body.empty()) res.set_content(std::to_string(res.status) + "\n", "text/plain");
    });
  }

  Options o_;
  std::mutex mutex_;  // guards state_ and timeline_ (LCM thread and HTTP threads)
  ViewerState state_;
  std::unique_ptr<LogTimeline> timeline_;
  ClientHub hub_;
};

}  // namespace

int main(int argc, char** argv) {
  cli::Program program("whiskeye-viewer",
                       "whiskeye-viewer: a web page of the robot's map, pose, camera, whiskers, events and daemons' "
                       "status, live over LCM or from a recorded log (docs/viewer.md)");
  CLI::App& app = program.app();
  Options o;
  app.add_option("--listen", o.listen, "ADDR:PORT to serve the page on (default 127.0.0.1:8088: this host only; port 0: any free one)");
  program.add_lcm_url(o.lcm_url);
  app.add_option("--log", o.log, "serve this recorded LCM log with a time slider instead of live LCM traffic")
      ->check(CLI::ExistingFile);
  app.add_option("--max-clients", o.max_clients, "live pages served at once; more are refused (default 8)")
      ->check(CLI::Range(1, 64));
  app.add_option("--queue", o.queue, "updates queued per page before a slow one skips to the current state (default 64)")
      ->check(CLI::Range(1, 10000));
  app.add_option("--update-ms", o.update_ms, "how often pages are sent what changed, ms (default 100)")
      ->check(CLI::Range(20, 10000));
  return program.run(argc, argv, [&] {
    if (!o.log.empty() && !o.lcm_url.empty()) {
      throw cli::UsageError("--log and --lcm-url exclude each other (a log is read, not received)");
    }
    return Viewer(o).run();
  });
}
