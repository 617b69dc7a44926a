// RobotinoClient over cpp-httplib: keep-alive, timeouts, and a classification of failures that the
// daemon can count (a timeout is not a refused connection is not a broken reply).
#include "whiskeye/based/robotino_client.h"

#include "whiskeye/common/clock.h"

#include <httplib.h>

namespace whiskeye::based {

const char* to_string(ReplyStatus status) {
  switch (status) {
    case ReplyStatus::kOk: return "ok";
    case ReplyStatus::kTimeout: return "timeout";
    case ReplyStatus::kDropped: return "dropped";
    case ReplyStatus::kConnectFailed: return "connect_failed";
    case ReplyStatus::kHttpError: return "http_error";
  }
  return "?";
}

struct RobotinoClient::Impl {
  httplib::Client client;
  std::string where;
  Impl(const BaseUrl& url) : client(url.host, url.port), where(url.host + ":" + std::to_string(url.port)) {}
};

static void split_seconds(double s, time_t& sec, time_t& usec) {
  const auto us = static_cast<int64_t>(s * 1e6);
  sec = static_cast<time_t>(us / 1000000);
  usec = static_cast<time_t>(us % 1000000);
}

RobotinoClient::RobotinoClient(const BaseUrl& url, double connect_timeout_s, double reply_timeout_s)
    : impl_(std::make_unique<Impl>(url)),
      connections_(std::make_shared<std::atomic<int64_t>>(0)),
      reply_timeout_s_(reply_timeout_s) {
  time_t sec = 0;
  time_t usec = 0;
  httplib::Client& c = impl_->client;
  c.set_keep_alive(true);
  c.set_tcp_nodelay(true);  // small requests at 50 Hz: no Nagle delay
  split_seconds(connect_timeout_s, sec, usec);
  c.set_connection_timeout(sec, usec);
  split_seconds(reply_timeout_s, sec, usec);
  c.set_read_timeout(sec, usec);
  c.set_write_timeout(sec, usec);
  // httplib calls this for every socket it opens: the count of (re)connections.
  c.set_socket_options([counter = connections_](socket_t) { counter->fetch_add(1); });
}

RobotinoClient::~RobotinoClient() = default;

namespace {

Reply classify(const httplib::Result& res, int64_t t0_us, double reply_timeout_s, const std::string& where) {
  Reply r;
  const int64_t t1_us = monotonic_us();
  r.recv_utime = now_utime();
  r.recv_mono_us = t1_us;
  r.round_trip_us = t1_us - t0_us;
  if (res) {
    r.http_status = res->status;
    r.body = res->body;
    if (res->status != 200) {
      r.status = ReplyStatus::kHttpError;
      r.error = "HTTP status " + std::to_string(res->status) + " from " + where;
    }
    return r;
  }
  const httplib::Error err = res.error();
  r.error = httplib::to_string(err) + " (" + where + ")";
  switch (err) {
    case httplib::Error::Connection:
    case httplib::Error::ConnectionTimeout:
    case httplib::Error::BindIPAddress:
      r.status = ReplyStatus::kConnectFailed;
      break;
    default:
      // httplib reports a read timeout and a closed connection alike (Read); the clock tells them apart.
      r.status = static_cast<double>(r.round_trip_us) >= 0.9e6 * reply_timeout_s ? ReplyStatus::kTimeout
                                                                                 : ReplyStatus::kDropped;
      break;
  }
  return r;
}

}  // namespace

Reply RobotinoClient::get(const std::string& path) {
  const int64_t t0 = monotonic_us();
  const httplib::Result res = impl_->client.Get(path.c_str());
  return classify(res, t0, reply_timeout_s_, impl_->where);
}

Reply RobotinoClient::post(const std::string& path, const std::string& json_body) {
  const int64_t t0 = monotonic_us();
  const httplib::Result res = impl_->client.Post(path.c_str(), json_body, "application/json");
  return classify(res, t0, reply_timeout_s_, impl_->where);
}

}  // namespace whiskeye::based
