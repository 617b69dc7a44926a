// The viewer's HTTP and Server-Sent Events API (docs/viewer.md, "How it works"): the page's files,
// /api/snapshot, /api/events, /api/camera.jpg and /status, over a ViewerState fed live (apply()) or
// a LogTimeline. Connections go through GatedServer (http_gate.h), which bounds what each client may
// hold; every request whose Host is not one the viewer serves on (AllowedHosts) is refused.
#pragma once

#include "whiskeye/viewer/allowed_hosts.h"
#include "whiskeye/viewer/client_hub.h"
#include "whiskeye/viewer/http_gate.h"
#include "whiskeye/viewer/log_timeline.h"
#include "whiskeye/viewer/viewer_state.h"

#include <cstdint>
#include <memory>
#include <mutex>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <thread>
#include <vector>

namespace whiskeye::viewer {

struct ServerOptions {
  std::string host = "127.0.0.1";  // as given to --listen (a name, an address; IPv6 without brackets)
  int port = 8088;                 // 0: any free one
  std::vector<std::string> allow_hosts;
  std::size_t max_clients = 8;
  std::size_t queue = 64;
  HttpLimits limits;  // workers: max_clients + 4 whatever is set here
};

// "ADDR:PORT" (or "[IPv6]:PORT") into `o.host` and `o.port`; false when malformed.
bool parse_listen(const std::string& s, ServerOptions& o);

class ViewerServer {
 public:
  // `timeline` null: live (fed by apply()); else the log it serves, `log_name` as shown to the page.
  ViewerServer(ServerOptions o, std::unique_ptr<LogTimeline> timeline = nullptr, std::string log_name = "");
  ~ViewerServer();
  ViewerServer(const ViewerServer&) = delete;
  ViewerServer& operator=(const ViewerServer&) = delete;

  // Binds and starts serving in a thread of its own; false (with `why`) when the address cannot be bound.
  bool start(std::string& why);
  // Ends every stream and stops serving.
  void stop();
  // The URLs it serves on (a wildcard address: one per interface). After start().
  std::vector<std::string> urls() const;

  // Live: one message received.
  void apply(std::string_view channel, int64_t recv_utime, std::span<const uint8_t> data);
  // Live: sends open pages what changed since the last call (at `now_us`, monotonic).
  void publish_changes(int64_t now_us);

  ClientHub::Stats hub_stats() const { return hub_.stats(); }
  GatedServer::Stats http_stats() const { return server_.stats(); }

 private:
  bool host_allowed(const std::string& host);
  // The state a request sees: live, the shared one; in a log, the timeline at ?t= (or where it is).
  // Called with mutex_ held; throws LogChanged when the log changed under the viewer.
  const ViewerState& state_for(const httplib::Request& req);
  nlohmann::json server_json() const;
  void routes();

  ServerOptions o_;
  std::string log_name_;
  mutable std::mutex mutex_;  // guards state_, cursor_ and timeline_ (LCM thread and HTTP workers)
  ViewerState state_;
  ViewerState::Cursor cursor_;
  std::unique_ptr<LogTimeline> timeline_;
  ClientHub hub_;
  GatedServer server_;
  std::mutex hosts_mutex_;
  std::optional<AllowedHosts> hosts_;
  int64_t hosts_read_us_ = 0;  // when the interfaces' addresses were last read
  std::thread http_;
};

}  // namespace whiskeye::viewer
