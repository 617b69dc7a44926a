// RobotinoClient over cpp-httplib: keep-alive, timeouts, and a classification of failures that the
// daemon can count (a timeout is not a refused connection is not a broken reply).
#include "whiskeye/based/robotino_client.h"

#include "whiskeye/common/clock.h"

#include <httplib.h>

#include <condition_variable>
#include <mutex>
#include <thread>

namespace whiskeye::based {

const char* to_string(ReplyStatus status) {
  switch (status) {
    case ReplyStatus::kOk: return "ok";
    case ReplyStatus::kTimeout: return "timeout";
    case ReplyStatus::kDropped: return "dropped";
    case ReplyStatus::kConnectFailed: return "connect_failed";
    case ReplyStatus::kHttpError: return "http_error";
    case ReplyStatus::kTooLarge: return "too_large";
  }
  return "?";
}

// Shuts the client's socket down when a request's deadline passes (httplib's stop() is the one call
// that is safe while another thread is inside a request). One thread per client, idle between requests.
class DeadlineWatchdog {
 public:
  explicit DeadlineWatchdog(httplib::Client& client) : client_(client), thread_([this] { run(); }) {}
  ~DeadlineWatchdog() {
    {
      std::lock_guard lock(mutex_);
      quit_ = true;
    }
    wake_.notify_one();
    thread_.join();
  }
  void arm(std::chrono::steady_clock::time_point deadline) {
    {
      std::lock_guard lock(mutex_);
      deadline_ = deadline;
      ++generation_;
      armed_ = true;
      fired_ = false;
    }
    wake_.notify_one();
  }
  // True if the deadline passed (and the socket was shut down) before disarm().
  bool disarm() {
    bool fired = false;
    {
      std::lock_guard lock(mutex_);
      armed_ = false;
      fired = fired_;
    }
    wake_.notify_one();
    return fired;
  }

 private:
  void run() {
    std::unique_lock lock(mutex_);
    for (;;) {
      wake_.wait(lock, [this] { return quit_ || (armed_ && !fired_); });
      if (quit_) return;
      const uint64_t request = generation_;
      // Woken early when the request ends (disarm), another one starts, or the client goes.
      if (wake_.wait_until(lock, deadline_, [&] { return quit_ || !armed_ || generation_ != request; })) continue;
      fired_ = true;
      client_.stop();  // the one httplib call safe during another thread's request
    }
  }

  httplib::Client& client_;
  std::mutex mutex_;
  std::condition_variable wake_;
  std::chrono::steady_clock::time_point deadline_;
  uint64_t generation_ = 0;  // which request the deadline belongs to
  bool armed_ = false;
  bool fired_ = false;
  bool quit_ = false;
  std::thread thread_;  // last: starts once the rest is built
};

struct RobotinoClient::Impl {
  httplib::Client client;
  std::string where;
  DeadlineWatchdog watchdog;
  Impl(const BaseUrl& url)
      : client(url.host, url.port), where(url.host + ":" + std::to_string(url.port)), watchdog(client) {}
};

static void split_seconds(double s, time_t& sec, time_t& usec) {
  const auto us = static_cast<int64_t>(s * 1e6);
  sec = static_cast<time_t>(us / 1000000);
  usec = static_cast<time_t>(us % 1000000);
}

RobotinoClient::RobotinoClient(const BaseUrl& url, double connect_timeout_s, double reply_timeout_s,
                               std::size_t max_body_bytes)
    : impl_(std::make_unique<Impl>(url)),
      connections_(std::make_shared<std::atomic<int64_t>>(0)),
      reply_timeout_s_(reply_timeout_s),
      max_body_bytes_(max_body_bytes) {
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

Reply RobotinoClient::get(const std::string& path) { return request("GET", path, nullptr); }

Reply RobotinoClient::post(const std::string& path, const std::string& json_body) {
  return request("POST", path, &json_body);
}

Reply RobotinoClient::request(const std::string& method, const std::string& path, const std::string* json_body) {
  httplib::Request req;
  req.method = method;
  req.path = path;
  if (json_body != nullptr) {
    req.body = *json_body;
    req.set_header("Content-Type", "application/json");
  }
  // The body as it comes, refused past the cap (httplib would otherwise buffer all of it first).
  std::string body;
  bool too_large = false;
  req.content_receiver = [&](const char* data, size_t n, uint64_t, uint64_t) {
    if (body.size() + n > max_body_bytes_) {
      too_large = true;
      return false;  // httplib cancels the request
    }
    body.append(data, n);
    return true;
  };
  const int64_t t0 = monotonic_us();
  // The deadline covers sending and the whole reply, and connecting: a connect under way holds the
  // lock httplib's stop() takes, so it runs to connect_timeout_s, and then the request is stopped.
  impl_->watchdog.arm(std::chrono::steady_clock::now() +
                      std::chrono::microseconds(static_cast<int64_t>(reply_timeout_s_ * 1e6)));
  httplib::Result res = impl_->client.send(req);
  const bool missed = impl_->watchdog.disarm();
  if (too_large) {
    Reply r = classify(res, t0, reply_timeout_s_, impl_->where);
    r.status = ReplyStatus::kTooLarge;
    r.body.clear();
    r.error = "reply body larger than " + std::to_string(max_body_bytes_) + " bytes, refused while reading (" +
              impl_->where + ")";
    return r;
  }
  if (missed && (!res || res->status == 200)) {
    ++deadlines_missed_;
    Reply r = classify(res, t0, reply_timeout_s_, impl_->where);
    r.status = ReplyStatus::kTimeout;
    r.body.clear();
    r.error = "no complete reply within " + std::to_string(reply_timeout_s_).substr(0, 5) + " s (" + impl_->where + ")";
    return r;
  }
  Reply r = classify(res, t0, reply_timeout_s_, impl_->where);
  if (res) r.body = std::move(body);
  return r;
}

}  // namespace whiskeye::based