// The viewer's HTTP connections: one poll loop, workers for whole requests (http_gate.h).
#include "whiskeye/viewer/http_gate.h"

#include <netdb.h>
#include <poll.h>
#include <sys/eventfd.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <stdexcept>
#include <string_view>

namespace whiskeye::viewer {

using Clock = std::chrono::steady_clock;

// One client connection. Its destructor closes it and takes what it still counts off the totals.
struct GatedServer::Conn {
  explicit Conn(GatedServer& s, int socket) : server(s), fd(socket) { ++server.connections_; }
  ~Conn() {
    drop_answer();
    ::close(fd);
    --server.connections_;
  }
  Conn(const Conn&) = delete;
  Conn& operator=(const Conn&) = delete;
  // The rest of the answer is not sent.
  void drop_answer() {
    server.buffered_ -= static_cast<int64_t>(out.size() - out_sent);
    out = std::string();
    out_sent = 0;
  }

  GatedServer& server;
  int fd;
  std::string in;               // received, not yet given to httplib
  std::size_t scanned = 0;      // `in` searched for the end of the headers up to here
  std::size_t request_len = 0;  // of the whole request at the front of `in`, once it is there
  std::string out;              // the answer; bytes [out_sent, end) are counted in buffered_
  std::size_t out_sent = 0;
  bool writing = false;      // sending `out`, else waiting for a request
  bool close_after = false;  // close once `out` is sent
  Clock::time_point deadline;
};

namespace {

int poll_ms(Clock::time_point until) {
  const auto left = std::chrono::ceil<std::chrono::milliseconds>(until - Clock::now()).count();
  return static_cast<int>(std::clamp<int64_t>(left, 0, 60'000));
}

bool wait_for(int fd, short events, Clock::time_point until) {
  for (;;) {
    pollfd p{fd, events, 0};
    const int r = ::poll(&p, 1, poll_ms(until));
    if (r > 0) return (p.revents & (POLLERR | POLLNVAL)) == 0 || (p.revents & events) != 0;
    if (r == 0 || errno != EINTR) return false;
  }
}

// A short answer written by the gate itself (no worker), then the connection is closed.
void refuse(int fd, int status, const char* reason) {
  const std::string body = std::to_string(status) + " " + reason + "\n";
  const std::string answer = "HTTP/1.1 " + std::to_string(status) + " " + reason +
                             "\r\nContent-Type: text/plain\r\nContent-Length: " + std::to_string(body.size()) +
                             "\r\nX-Content-Type-Options: nosniff\r\nCache-Control: no-store\r\nConnection: close\r\n\r\n" + body;
  // Best effort: a client that does not take these few bytes at once loses them.
  [[maybe_unused]] const ssize_t n = ::send(fd, answer.data(), answer.size(), MSG_NOSIGNAL | MSG_DONTWAIT);
}

char lower(char c) { return (c >= 'A' && c <= 'Z') ? static_cast<char>(c - 'A' + 'a') : c; }

// The value of header `name` (lower case, with the colon) in `head` (the request line and headers,
// CRLF-separated), or npos-empty when absent.
bool header_value(std::string_view head, std::string_view name, std::string_view& value) {
  std::size_t at = head.find("\r\n");
  while (at != std::string_view::npos && at + 2 < head.size()) {
    const std::size_t start = at + 2;
    const std::size_t end = std::min(head.find("\r\n", start), head.size());
    const std::string_view line = head.substr(start, end - start);
    if (line.size() >= name.size() &&
        std::equal(name.begin(), name.end(), line.begin(), [](char a, char b) { return a == lower(b); })) {
      value = line.substr(name.size());
      while (!value.empty() && (value.front() == ' ' || value.front() == '\t')) value.remove_prefix(1);
      return true;
    }
    at = end;
  }
  return false;
}

void ip_and_port(const sockaddr_storage& a, socklen_t len, std::string& ip, int& port) {
  char host[NI_MAXHOST], serv[NI_MAXSERV];
  if (::getnameinfo(reinterpret_cast<const sockaddr*>(&a), len, host, sizeof host, serv, sizeof serv,
                    NI_NUMERICHOST | NI_NUMERICSERV) == 0) {
    ip = host;
    port = std::atoi(serv);
  }
}

}  // namespace

// httplib's view of one request on a connection: the request's bytes as the gate received them,
// the answer into the connection's buffer (or, for a long-lived answer, to the socket as produced).
class GateStream : public httplib::Stream {
 public:
  GateStream(GatedServer& server, GatedServer::Conn& conn) : server_(server), conn_(conn) {}

  void set_stream(bool on) { stream_ = on; }
  bool is_stream() const { return stream_; }
  bool failed() const { return failed_; }
  std::size_t consumed() const { return read_at_; }

  bool is_readable() const override { return read_at_ < conn_.in.size(); }
  bool is_writable() const override {
    if (!stream_) return !failed_;
    if (!wait_for(conn_.fd, POLLOUT, Clock::now() + server_.limits_.stream_write_timeout)) return false;
    char c;  // a peer that closed its end reads as end of file
    return ::recv(conn_.fd, &c, 1, MSG_PEEK | MSG_DONTWAIT) != 0;
  }
  ssize_t read(char* ptr, size_t size) override {
    const std::size_t n = std::min(size, conn_.in.size() - read_at_);
    std::memcpy(ptr, conn_.in.data() + read_at_, n);
    read_at_ += n;
    return static_cast<ssize_t>(n);
  }
  ssize_t write(const char* ptr, size_t size) override {
    if (failed_) return -1;
    if (stream_) return send_now(ptr, size, Clock::now() + server_.limits_.stream_write_timeout);
    // As much as the socket takes now; the rest waits in the connection for the poll loop to send.
    std::size_t done = 0;
    if (conn_.out_sent == conn_.out.size()) {
      const ssize_t k = ::send(conn_.fd, ptr, size, MSG_NOSIGNAL | MSG_DONTWAIT);
      if (k > 0) {
        done = static_cast<std::size_t>(k);
      } else if (k < 0 && errno != EAGAIN && errno != EWOULDBLOCK && errno != EINTR) {
        failed_ = true;
        return -1;
      }
    }
    const std::size_t rest = size - done;
    if (rest == 0) return static_cast<ssize_t>(size);
    // Answers waiting for their clients are bounded over all connections: past the bound this one
    // is cut (its connection closed), rather than a worker waiting for a slow reader.
    if (server_.buffered_.load() + static_cast<int64_t>(rest) > static_cast<int64_t>(server_.limits_.max_buffered_bytes)) {
      ++server_.over_budget_;
      failed_ = true;
      return -1;
    }
    conn_.out.append(ptr + done, rest);
    server_.buffered_ += static_cast<int64_t>(rest);
    return static_cast<ssize_t>(size);
  }
  void get_remote_ip_and_port(std::string& ip, int& port) const override {
    sockaddr_storage a{};
    socklen_t len = sizeof a;
    if (::getpeername(conn_.fd, reinterpret_cast<sockaddr*>(&a), &len) == 0) ip_and_port(a, len, ip, port);
  }
  void get_local_ip_and_port(std::string& ip, int& port) const override {
    sockaddr_storage a{};
    socklen_t len = sizeof a;
    if (::getsockname(conn_.fd, reinterpret_cast<sockaddr*>(&a), &len) == 0) ip_and_port(a, len, ip, port);
  }
  socket_t socket() const override { return conn_.fd; }

 private:
  // Sends all of it before `until`; -1 (and the connection is done) otherwise.
  ssize_t send_now(const char* p, std::size_t n, Clock::time_point until) {
    std::size_t done = 0;
    while (done < n) {
      const ssize_t k = ::send(conn_.fd, p + done, n - done, MSG_NOSIGNAL | MSG_DONTWAIT);
      if (k > 0) {
        done += static_cast<std::size_t>(k);
      } else if (k < 0 && errno == EINTR) {
        continue;
      } else if (k < 0 && (errno == EAGAIN || errno == EWOULDBLOCK) && wait_for(conn_.fd, POLLOUT, until)) {
        continue;
      } else {
        failed_ = true;
        return -1;
      }
    }
    return static_cast<ssize_t>(n);
  }

  GatedServer& server_;
  GatedServer::Conn& conn_;
  std::size_t read_at_ = 0;
  bool stream_ = false;
  bool failed_ = false;
};

namespace {

// httplib's accept loop hands each socket to the task queue: taking it is immediate (the poll loop
// gets it), so it runs on the accepting thread.
class Inline : public httplib::TaskQueue {
 public:
  void enqueue(std::function<void()> fn) override { fn(); }
  void shutdown() override {}
};

}  // namespace

GatedServer::GatedServer(HttpLimits limits, std::function<bool(const httplib::Request&)> is_stream)
    : limits_(limits), is_stream_(std::move(is_stream)) {
  wake_fd_ = ::eventfd(0, EFD_CLOEXEC | EFD_NONBLOCK);
  if (wake_fd_ < 0) throw std::runtime_error(std::string("eventfd: ") + std::strerror(errno));
  new_task_queue = [] { return new Inline; };
  poller_ = std::thread([this] { poll_loop(); });
  for (std::size_t i = 0; i < std::max<std::size_t>(1, limits_.workers); ++i) workers_.emplace_back([this] { worker_loop(); });
}

GatedServer::~GatedServer() {
  shutdown();
  ::close(wake_fd_);
}

void GatedServer::shutdown() {
  {
    std::lock_guard lock(mutex_);
    if (stopping_ && !poller_.joinable()) return;
    stopping_ = true;
  }
  work_.notify_all();
  wake();
  if (poller_.joinable()) poller_.join();
  for (auto& w : workers_) {
    if (w.joinable()) w.join();
  }
  std::lock_guard lock(mutex_);
  for (int fd : accepted_) ::close(fd);
  accepted_.clear();
  returned_.clear();
  waiting_.clear();
}

void GatedServer::set_backlog(int connections) { ::listen(svr_sock_.load(), connections); }

sockaddr_storage GatedServer::bound_address() const {
  sockaddr_storage a{};
  socklen_t len = sizeof a;
  ::getsockname(svr_sock_.load(), reinterpret_cast<sockaddr*>(&a), &len);
  return a;
}

GatedServer::Stats GatedServer::stats() const {
  return {connections_.load(), timed_out_.load(),    too_large_.load(),   evicted_.load(),
          busy_.load(),        slow_readers_.load(), over_budget_.load(), buffered_.load()};
}

void GatedServer::wake() {
  const uint64_t one = 1;
  [[maybe_unused]] const ssize_t n = ::write(wake_fd_, &one, sizeof one);
}

bool GatedServer::process_and_close_socket(socket_t sock) {
  {
    std::lock_guard lock(mutex_);
    if (stopping_) {
      ::close(sock);
      return false;
    }
    accepted_.push_back(sock);
  }
  wake();
  return true;
}

void GatedServer::give_back(std::unique_ptr<Conn> conn) {
  {
    std::lock_guard lock(mutex_);
    returned_.push_back(std::move(conn));
  }
  wake();
}

GatedServer::Verdict GatedServer::check_request(std::unique_ptr<Conn>& c) {
  const std::size_t from = c->scanned > 3 ? c->scanned - 3 : 0;
  const std::size_t end = c->in.find("\r\n\r\n", from);
  const std::size_t head_len = end == std::string::npos ? c->in.size() : end + 4;
  std::size_t fields = 0;
  for (std::size_t at = c->in.find("\r\n"); at != std::string::npos && at < head_len; at = c->in.find("\r\n", at + 2)) ++fields;
  c->scanned = c->in.size();
  if (head_len > limits_.max_header_bytes || fields > limits_.max_header_fields + 1) {
    ++too_large_;
    refuse(c->fd, 431, "Request Header Fields Too Large");
    return Verdict::kRefused;
  }
  if (end == std::string::npos) return Verdict::kIncomplete;
  const std::string_view head(c->in.data(), head_len);
  std::string_view value;
  std::size_t body = 0;
  if (header_value(head, "transfer-encoding:", value)) {  // it takes no uploads, chunked or not
    ++too_large_;
    refuse(c->fd, 413, "Payload Too Large");
    return Verdict::kRefused;
  }
  if (header_value(head, "content-length:", value)) {
    for (char ch : value) {
      if (ch < '0' || ch > '9' || body > limits_.max_body_bytes) break;
      body = body * 10 + static_cast<std::size_t>(ch - '0');
    }
    if (body > limits_.max_body_bytes) {
      ++too_large_;
      refuse(c->fd, 413, "Payload Too Large");
      return Verdict::kRefused;
    }
  }
  if (c->in.size() < head_len + body) return Verdict::kIncomplete;
  c->request_len = head_len + body;
  {
    std::lock_guard lock(mutex_);
    if (waiting_.size() < limits_.max_waiting_requests) {
      waiting_.push_back(std::move(c));
      work_.notify_one();
      return Verdict::kDispatched;
    }
  }
  ++busy_;
  refuse(c->fd, 503, "Service Unavailable");
  return Verdict::kRefused;
}

void GatedServer::poll_loop() {
  std::vector<std::unique_ptr<Conn>> conns;
  std::vector<pollfd> fds;
  const auto admit = [&](std::unique_ptr<Conn> c) {
    // Full: the connection that has waited longest for its request (or for its answer to be taken) goes.
    if (conns.size() >= limits_.max_connections) {
      const auto oldest = std::min_element(conns.begin(), conns.end(), [](const auto& a, const auto& b) { return a->deadline < b->deadline; });
      ++evicted_;
      conns.erase(oldest);
    }
    conns.push_back(std::move(c));
  };
  // A connection whose request is refused is closed; one handed to a worker is no longer here.
  const auto go_on = [&](std::unique_ptr<Conn>& c) {
    if (check_request(c) == Verdict::kRefused) c.reset();
  };

  char buf[16384];
  for (;;) {
    {
      std::lock_guard lock(mutex_);
      if (stopping_) break;
      for (int fd : accepted_) {
        auto c = std::make_unique<Conn>(*this, fd);
        c->deadline = Clock::now() + limits_.request_timeout;
        admit(std::move(c));
      }
      accepted_.clear();
      for (auto& c : returned_) admit(std::move(c));
      returned_.clear();
    }
    // Given back with the next request already read (pipelined): it goes on at once.
    for (auto& c : conns) {
      if (!c->writing && c->scanned < c->in.size()) go_on(c);
    }
    std::erase(conns, nullptr);

    fds.assign(1, pollfd{wake_fd_, POLLIN, 0});
    Clock::time_point next = Clock::now() + std::chrono::seconds(60);
    for (const auto& c : conns) {
      fds.push_back({c->fd, static_cast<short>(c->writing ? POLLOUT : POLLIN), 0});
      next = std::min(next, c->deadline);
    }
    if (::poll(fds.data(), fds.size(), poll_ms(next)) < 0 && errno != EINTR) break;
    if (fds[0].revents & POLLIN) {
      uint64_t v;
      [[maybe_unused]] const ssize_t n = ::read(wake_fd_, &v, sizeof v);
    }
    const auto now = Clock::now();
    for (std::size_t i = 0; i < conns.size(); ++i) {
      auto& c = conns[i];
      const short ev = fds[i + 1].revents;
      if (c->writing && (ev & (POLLOUT | POLLERR | POLLHUP))) {
        const ssize_t k = ::send(c->fd, c->out.data() + c->out_sent, c->out.size() - c->out_sent, MSG_NOSIGNAL | MSG_DONTWAIT);
        if (k < 0 && errno != EAGAIN && errno != EINTR) {
          c.reset();
          continue;
        }
        if (k > 0) {
          c->out_sent += static_cast<std::size_t>(k);
          buffered_ -= k;
        }
        if (c->out_sent == c->out.size()) {
          if (c->close_after) {
            c.reset();
            continue;
          }
          c->drop_answer();
          c->writing = false;
          c->deadline = now + limits_.request_timeout;
          if (!c->in.empty()) go_on(c);
          if (!c) continue;
        }
      } else if (!c->writing && (ev & (POLLIN | POLLERR | POLLHUP))) {
        const ssize_t k = ::recv(c->fd, buf, sizeof buf, MSG_DONTWAIT);
        if (k == 0 || (k < 0 && errno != EAGAIN && errno != EINTR)) {
          c.reset();
          continue;
        }
        if (k > 0) {
          c->in.append(buf, static_cast<std::size_t>(k));
          go_on(c);
          if (!c) continue;
        }
      }
      if (now >= c->deadline) {
        if (c->writing) {
          ++slow_readers_;
        } else if (!c->in.empty()) {
          ++timed_out_;
          refuse(c->fd, 408, "Request Timeout");
        }
        c.reset();
      }
    }
    std::erase(conns, nullptr);
  }
}

void GatedServer::worker_loop() {
  for (;;) {
    std::unique_ptr<Conn> conn;
    {
      std::unique_lock lock(mutex_);
      work_.wait(lock, [this] { return stopping_ || !waiting_.empty(); });
      if (stopping_) return;
      conn = std::move(waiting_.front());
      waiting_.pop_front();
    }
    serve(std::move(conn));
  }
}

void GatedServer::serve(std::unique_ptr<Conn> conn) {
  GateStream strm(*this, *conn);
  bool closed = false;
  const bool ok = process_request(strm, false, closed, [this, &strm](httplib::Request& req) {
    req.ranges.clear();
    strm.set_stream(is_stream_ && is_stream_(req));
  });
  conn->in.erase(0, std::max(strm.consumed(), conn->request_len));
  conn->scanned = 0;
  conn->request_len = 0;
  // A long-lived answer ends with its connection; so does a failed one.
  conn->close_after = !ok || closed || strm.failed() || strm.is_stream();
  if (strm.failed()) conn->drop_answer();
  if (conn->out_sent == conn->out.size()) {
    if (conn->close_after) return;  // closed by its destructor
    conn->drop_answer();
    conn->deadline = Clock::now() + limits_.request_timeout;
  } else {
    conn->writing = true;
    conn->deadline = Clock::now() + limits_.response_timeout;
  }
  give_back(std::move(conn));
}

}  // namespace whiskeye::viewer
