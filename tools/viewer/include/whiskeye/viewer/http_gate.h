// The viewer's HTTP connections, bounded so that no client can hold back another. cpp-httplib parses,
// routes and writes each request (Server::process_request over a Stream of this file); what it does
// per connection (a pool thread reading the request byte by byte, then writing the answer, for as long
// as the client takes) is replaced by one poll loop that
//   - hands a request to a worker thread only once it has arrived whole (line, headers, body), within
//     `request_timeout` of the connection being ready for it: a client sending slowly costs a socket
//     and a buffer, never a worker; past the deadline it gets 408 and is closed;
//   - refuses a request whose line and headers pass `max_header_bytes` or `max_header_fields` (431),
//     or that carries a body larger than `max_body_bytes` or chunked (413), as soon as it shows, so
//     memory is bounded by the limits, not by what a client sends;
//   - sends the answer a worker produced (the worker does not wait for the client): what the socket
//     does not take at once waits in the connection, at most `max_buffered_bytes` over all
//     connections (past it an answer is cut and its connection closed), and a client that has not
//     taken its answer within `response_timeout` is closed;
//   - keeps at most `max_connections` open; a new one closes the one that has waited longest.
// Long-lived answers (`is_stream`: the event stream) are written by their worker as they are
// produced, a write blocked for `stream_write_timeout` closing them; their number is the caller's to
// bound (ClientHub). A Range header is ignored: every answer is whole (cpp-httplib 0.11 does not clamp
// a range to the content, and many ranges multiply the answer).
#pragma once

#include <httplib.h>

#include <sys/socket.h>

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <deque>
#include <functional>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

namespace whiskeye::viewer {

struct HttpLimits {
  std::chrono::milliseconds request_timeout{5000};    // a whole request, from accept or the previous answer
  std::chrono::milliseconds response_timeout{30000};  // a whole answer taken by the client
  std::chrono::milliseconds stream_write_timeout{5000};
  std::size_t max_header_bytes = 32 * 1024;  // request line and headers
  std::size_t max_header_fields = 100;
  std::size_t max_body_bytes = 1024;
  std::size_t max_connections = 256;
  std::size_t max_buffered_bytes = 64u << 20;  // answers waiting for their clients, all connections
  std::size_t workers = 12;
  std::size_t max_waiting_requests = 64;  // whole requests waiting for a worker; beyond, 503
};

class GatedServer : public httplib::Server {
 public:
  GatedServer(HttpLimits limits, std::function<bool(const httplib::Request&)> is_stream);
  ~GatedServer() override;
  GatedServer(const GatedServer&) = delete;
  GatedServer& operator=(const GatedServer&) = delete;

  // Stops the poll loop and the workers and closes every connection; after Server::stop() and the
  // end of listen_after_bind(). A worker in a long-lived answer must be ended by the caller first.
  void shutdown();

  // The listening socket's queue of connections not yet accepted (cpp-httplib listens with 5, which
  // a burst of connections overflows: the kernel then delays them by seconds). After bind.
  void set_backlog(int connections);
  // The listening socket's address (after bind_to_port / bind_to_any_port).
  sockaddr_storage bound_address() const;

  struct Stats {
    int64_t connections = 0;     // open now
    int64_t timed_out = 0;       // 408: a request not whole in time
    int64_t too_large = 0;       // 431 / 413
    int64_t evicted = 0;         // closed for a newer connection
    int64_t busy = 0;            // 503: no worker free and the waiting line full
    int64_t slow_readers = 0;    // closed with an answer not taken in time
    int64_t over_budget = 0;     // answers cut: max_buffered_bytes reached
    int64_t buffered_bytes = 0;  // answers waiting for their clients
  };
  Stats stats() const;
  const HttpLimits& limits() const { return limits_; }

  struct Conn;  // one client connection (http_gate.cpp)

 private:
  bool process_and_close_socket(socket_t sock) override;
  enum class Verdict { kIncomplete, kDispatched, kRefused };
  // Whether the request at the front of `c->in` has arrived whole; a whole one goes to the workers
  // (`c` is then empty), one that cannot be served is answered here (and is to be closed).
  Verdict check_request(std::unique_ptr<Conn>& c);
  void poll_loop();
  void worker_loop();
  void serve(std::unique_ptr<Conn> conn);
  void give_back(std::unique_ptr<Conn> conn);
  void wake();

  HttpLimits limits_;
  std::function<bool(const httplib::Request&)> is_stream_;
  int wake_fd_ = -1;  // eventfd: new or returned connections, or shutdown

  std::mutex mutex_;  // guards the three queues below and stopping_
  std::vector<int> accepted_;
  std::vector<std::unique_ptr<Conn>> returned_;
  std::deque<std::unique_ptr<Conn>> waiting_;  // whole requests for the workers
  std::condition_variable work_;
  bool stopping_ = false;

  std::thread poller_;
  std::vector<std::thread> workers_;
  std::atomic<int64_t> connections_{0}, timed_out_{0}, too_large_{0}, evicted_{0}, busy_{0}, slow_readers_{0},
      over_budget_{0};
  std::atomic<int64_t> buffered_{0};
  friend class GateStream;
  friend struct Conn;
};

}  // namespace whiskeye::viewer
