// The viewer's HTTP and Server-Sent Events API (viewer_server.h).
#include "whiskeye/viewer/viewer_server.h"

#include "whiskeye/common/clock.h"
#include "whiskeye/viewer/assets.h"

#include <unistd.h>

#include <chrono>

namespace whiskeye::viewer {

using nlohmann::json;

namespace {

// Headers every answer carries: the page loads nothing from elsewhere, nothing is cached, and no
// answer is a range of itself.
void harden(httplib::Response& res) {
  res.set_header("X-Content-Type-Options", "nosniff");
  res.set_header("Content-Security-Policy", "default-src 'self'; img-src 'self'; style-src 'self'; script-src 'self'");
  res.set_header("Cache-Control", "no-store");
  res.set_header("Referrer-Policy", "no-referrer");
  res.set_header("Accept-Ranges", "none");
}

std::string sse(const char* event, const std::string& data) {
  return std::string("event: ") + event + "\ndata: " + data + "\n\n";
}

void error(httplib::Response& res, int status, const std::string& text) {
  res.status = status;
  res.set_content(text + "\n", "text/plain");
}

std::string host_name() {
  char name[256] = "";
  if (::gethostname(name, sizeof name - 1) != 0) return "";
  return name;
}

bool is_event_stream(const httplib::Request& req) { return req.path == "/api/events"; }

}  // namespace

bool parse_listen(const std::string& s, ServerOptions& o) {
  const auto colon = s.rfind(':');
  if (colon == std::string::npos || colon == 0 || colon + 1 == s.size()) return false;
  std::string host = s.substr(0, colon);
  if (host.size() > 2 && host.front() == '[' && host.back() == ']') host = host.substr(1, host.size() - 2);
  try {
    std::size_t used = 0;
    const int port = std::stoi(s.substr(colon + 1), &used);
    if (used != s.size() - colon - 1 || port < 0 || port > 65535) return false;
    o.host = host;
    o.port = port;
    return true;
  } catch (const std::exception&) {
    return false;
  }
}

namespace {
HttpLimits with_workers(HttpLimits l, std::size_t max_clients) {
  // One worker per live page (its stream), and a few for everything else.
  l.workers = max_clients + 4;
  return l;
}
}  // namespace

ViewerServer::ViewerServer(ServerOptions o, std::unique_ptr<LogTimeline> timeline, std::string log_name)
    : o_(std::move(o)),
      log_name_(std::move(log_name)),
      timeline_(std::move(timeline)),
      hub_(o_.max_clients, o_.queue),
      server_(with_workers(o_.limits, o_.max_clients), is_event_stream) {
  server_.set_write_timeout(std::chrono::duration_cast<std::chrono::seconds>(o_.limits.stream_write_timeout).count(), 0);
  server_.set_payload_max_length(o_.limits.max_body_bytes);  // it takes no uploads
  routes();
}

ViewerServer::~ViewerServer() { stop(); }

bool ViewerServer::start(std::string& why) {
  int port = o_.port;
  if (port == 0) {
    port = server_.bind_to_any_port(o_.host);
  } else if (!server_.bind_to_port(o_.host, port)) {
    port = -1;
  }
  if (port < 0) {
    why = "cannot listen on " + o_.host + ":" + std::to_string(o_.port) + " (address in use or not on this host)";
    return false;
  }
  server_.set_backlog(128);
  hosts_.emplace(server_.bound_address(), o_.host, o_.allow_hosts, interface_addresses(server_.bound_address().ss_family == AF_INET6),
                 host_name());
  hosts_read_us_ = monotonic_us();
  http_ = std::thread([this] { server_.listen_after_bind(); });
  return true;
}

void ViewerServer::stop() {
  if (!http_.joinable()) return;
  hub_.close_all();
  server_.stop();
  http_.join();
  server_.shutdown();
}

std::vector<std::string> ViewerServer::urls() const { return hosts_ ? hosts_->urls() : std::vector<std::string>{}; }

const ViewerState& ViewerServer::state_for(const httplib::Request& req) {
  if (!timeline_) return state_;
  if (!timeline_->changed().empty()) throw LogChanged(timeline_->changed());
  if (req.has_param("t")) {
    try {
      return timeline_->seek(std::stoll(req.get_param_value("t")));
    } catch (const std::invalid_argument&) {
    } catch (const std::out_of_range&) {
    }
  }
  return timeline_->state();
}

bool ViewerServer::host_allowed(const std::string& host) {
  std::lock_guard lock(hosts_mutex_);
  if (hosts_->allows(host)) return true;
  // Serving on every interface: an address gained since (DHCP after start) counts; read again at
  // most once a second, so a stream of foreign names costs nothing.
  const int64_t now = monotonic_us();
  if (!hosts_->wildcard() || now - hosts_read_us_ < 1'000'000) return false;
  hosts_read_us_ = now;
  hosts_.emplace(server_.bound_address(), o_.host, o_.allow_hosts, interface_addresses(server_.bound_address().ss_family == AF_INET6),
                 host_name());
  return hosts_->allows(host);
}

void ViewerServer::apply(std::string_view channel, int64_t recv_utime, std::span<const uint8_t> data) {
  std::lock_guard lock(mutex_);
  state_.apply(channel, recv_utime, data);
}

void ViewerServer::publish_changes(int64_t now_us) {
  std::lock_guard lock(mutex_);
  state_.set_now(now_utime());
  // With no page open nothing is built (a page that connects starts from the whole state).
  if (hub_.clients() == 0) return;
  json delta = state_.delta(cursor_, now_us);
  if (!delta.empty()) hub_.broadcast(std::make_shared<const std::string>(sse("delta", delta.dump())));
}

json ViewerServer::server_json() const {
  const ClientHub::Stats s = hub_.stats();
  json clients = json::array();
  for (const auto& c : s.per_client) clients.push_back({{"id", c.id}, {"sent", c.sent}, {"dropped", c.dropped}, {"resyncs", c.resyncs}});
  const GatedServer::Stats h = server_.stats();
  json out = {{"mode", timeline_ ? "log" : "live"},
              {"clients", s.clients},
              {"max_clients", s.max_clients},
              {"queue_capacity", s.queue_capacity},
              {"joined", s.joined},
              {"refused", s.refused},
              {"updates", s.broadcasts},
              {"dropped", s.dropped},
              {"per_client", std::move(clients)},
              {"http",
               {{"connections", h.connections},
                {"timed_out", h.timed_out},
                {"too_large", h.too_large},
                {"evicted", h.evicted},
                {"busy", h.busy},
                {"slow_readers", h.slow_readers},
                {"over_budget", h.over_budget},
                {"buffered_bytes", h.buffered_bytes}}}};
  if (timeline_) {
    out["log"] = {{"file", log_name_},
                  {"start", timeline_->start_utime()},
                  {"end", timeline_->end_utime()},
                  {"events", timeline_->events()},
                  {"damage", timeline_->damage()},
                  {"error", timeline_->changed()}};
  }
  return out;
}

void ViewerServer::routes() {
  httplib::Server& server = server_;
  // Before any route: a Host the viewer does not serve on is a page of another site (DNS rebinding).
  server.set_pre_routing_handler([this](const httplib::Request& req, httplib::Response& res) {
    const bool has_host = req.has_header("Host");
    if (has_host ? host_allowed(req.get_header_value("Host")) : req.version == "HTTP/1.0") {
      return httplib::Server::HandlerResponse::Unhandled;
    }
    harden(res);
    error(res, has_host ? 403 : 400,
          has_host ? "host not allowed: " + req.get_header_value("Host") + " (the viewer answers the names it serves on and --allow-host)"
                   : "no Host header");
    return httplib::Server::HandlerResponse::Handled;
  });
  // In a log that changed under the viewer, the state cannot be shown: the page shows why instead.
  const auto log_changed = [this](httplib::Response& res, const std::string& why) {
    json out = {{"error", why}, {"server", server_json()}};
    res.status = 503;
    res.set_content(out.dump(), "application/json");
  };
  server.Get("/api/snapshot", [this, log_changed](const httplib::Request& req, httplib::Response& res) {
    harden(res);
    json snap;
    try {
      std::lock_guard lock(mutex_);
      snap = state_for(req).snapshot();
    } catch (const LogChanged& e) {
      return log_changed(res, e.what());
    }
    snap["server"] = server_json();
    res.set_content(snap.dump(), "application/json");
  });
  server.Get("/status", [this](const httplib::Request&, httplib::Response& res) {
    harden(res);
    json out = server_json();
    {
      std::lock_guard lock(mutex_);
      const ViewerState& s = timeline_ ? timeline_->state() : state_;
      out["meta"] = s.section(ViewerState::kMeta);
      out["status"] = s.section(ViewerState::kStatus);
      out["num_experiences"] = s.num_experiences();
    }
    res.set_content(out.dump(2) + "\n", "application/json");
  });
  server.Get("/api/camera.jpg", [this, log_changed](const httplib::Request& req, httplib::Response& res) {
    harden(res);
    std::shared_ptr<const std::string> jpeg;
    try {
      std::lock_guard lock(mutex_);
      jpeg = state_for(req).camera_jpeg();
    } catch (const LogChanged& e) {
      return log_changed(res, e.what());
    }
    if (!jpeg) return error(res, 404, "no camera frame");
    // The pointer keeps the bytes alive while they are sent, after the lock is released.
    res.set_content_provider(jpeg->size(), "image/jpeg", [jpeg](std::size_t offset, std::size_t length, httplib::DataSink& sink) {
      return sink.write(jpeg->data() + offset, length);
    });
  });
  server.Get("/api/events", [this](const httplib::Request&, httplib::Response& res) {
    harden(res);
    if (timeline_) return error(res, 404, "a log has no live updates: use /api/snapshot?t=");
    std::shared_ptr<ClientQueue> client = hub_.join();
    if (!client) return error(res, 503, "too many viewers (--max-clients)");
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
    if (!asset) return error(res, 404, "not found");
    res.set_content(asset->body.data(), asset->body.size(), std::string(asset->content_type).c_str());
  });
  server.set_error_handler([](const httplib::Request&, httplib::Response& res) {
    harden(res);
    if (res.body.empty()) res.set_content(std::to_string(res.status) + "\n", "text/plain");
  });
}

}  // namespace whiskeye::viewer
