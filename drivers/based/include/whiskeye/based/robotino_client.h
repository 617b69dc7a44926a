// One kept-alive HTTP connection to the Robotino's REST server (cpp-httplib underneath). Each call
// is one request with bounded connect and reply times; failures come back classified, never thrown.
// Not thread-safe: each thread that talks to the base owns its own client (its own connection).
//
// reply_timeout_s is a deadline on the whole request, not on each read: a server sending one byte
// every 50 ms would otherwise hold the calling thread for as long as it likes (the odometry thread's
// watchdog keep-alives stopped, and systemd restarted based again and again). A watchdog thread of
// the client's own shuts the socket down when the deadline passes. The reply body is capped while it
// is read (max_body_bytes, 4 KiB for the base's seven numbers): a 100 MB reply is refused at its
// 4,097th byte instead of being buffered first.
#pragma once

#include "whiskeye/based/protocol.h"

#include <atomic>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>

namespace whiskeye::based {

enum class ReplyStatus {
  kOk,             // a complete reply with status 200
  kTimeout,        // no complete reply within the reply timeout
  kDropped,        // the connection broke before a complete reply
  kConnectFailed,  // could not connect (refused, unreachable, connect timeout)
  kHttpError,      // a complete reply with a status other than 200
  kTooLarge,       // the reply body passed max_body_bytes: refused while it was read
};

const char* to_string(ReplyStatus status);

struct Reply {
  ReplyStatus status = ReplyStatus::kOk;
  int http_status = 0;
  std::string body;
  std::string error;        // what went wrong, for logs
  int64_t recv_utime = 0;   // wall clock when the reply (or the failure) came: for timestamps only
  int64_t recv_mono_us = 0; // the same instant on the monotonic clock: for intervals and timeouts
  int64_t round_trip_us = 0;
};

class RobotinoClient {
 public:
  RobotinoClient(const BaseUrl& url, double connect_timeout_s, double reply_timeout_s,
                 std::size_t max_body_bytes = kMaxReplyBytes);
  ~RobotinoClient();
  RobotinoClient(const RobotinoClient&) = delete;
  RobotinoClient& operator=(const RobotinoClient&) = delete;

  Reply get(const std::string& path);
  Reply post(const std::string& path, const std::string& json_body);
  // Requests cut off at their deadline so far.
  int64_t deadlines_missed() const { return deadlines_missed_; }

  // Sockets opened so far, failed connects included (stays 1 while the kept-alive connection holds).
  int64_t connections_opened() const { return connections_->load(); }

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
  Reply request(const std::string& method, const std::string& path, const std::string* json_body);

  std::shared_ptr<std::atomic<int64_t>> connections_;
  double reply_timeout_s_;
  std::size_t max_body_bytes_;
  int64_t deadlines_missed_ = 0;
};

}  // namespace whiskeye::based
