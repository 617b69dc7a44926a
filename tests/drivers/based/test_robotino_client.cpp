// RobotinoClient against hostile servers on loopback TCP: a reply dripped one byte at a time, and
// a reply far larger than any the base sends.
#include "whiskeye/based/robotino_client.h"

#include "whiskeye/common/clock.h"

#include <gtest/gtest.h>

#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <functional>
#include <string>
#include <thread>

namespace whiskeye::based {
namespace {

using namespace std::chrono_literals;

// A one-connection-at-a-time TCP server on 127.0.0.1 that reads a request and answers with `serve`.
class RawServer {
 public:
  explicit RawServer(std::function<void(int fd, const std::atomic<bool>& stop)> serve) : serve_(std::move(serve)) {
    listen_fd_ = ::socket(AF_INET, SOCK_STREAM, 0);
    sockaddr_in a{};
    a.sin_family = AF_INET;
    a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    a.sin_port = 0;
    EXPECT_EQ(::bind(listen_fd_, reinterpret_cast<sockaddr*>(&a), sizeof a), 0);
    EXPECT_EQ(::listen(listen_fd_, 4), 0);
    socklen_t len = sizeof a;
    ::getsockname(listen_fd_, reinterpret_cast<sockaddr*>(&a), &len);
    port_ = ntohs(a.sin_port);
    thread_ = std::thread([this] {
      while (!stop_) {
        const int fd = ::accept(listen_fd_, nullptr, nullptr);
        if (fd < 0) break;
        char buf[4096];
        (void)::recv(fd, buf, sizeof buf, 0);  // the request (small): not looked at
        serve_(fd, stop_);
        ::close(fd);
      }
    });
  }
  ~RawServer() {
    stop_ = true;
    ::shutdown(listen_fd_, SHUT_RDWR);
    ::close(listen_fd_);
    thread_.join();
  }
  BaseUrl url() const { return BaseUrl{"127.0.0.1", port_}; }

 private:
  std::function<void(int, const std::atomic<bool>&)> serve_;
  int listen_fd_ = -1;
  int port_ = 0;
  std::atomic<bool> stop_{false};
  std::thread thread_;
};

bool send_all(int fd, const std::string& s) { return ::send(fd, s.data(), s.size(), MSG_NOSIGNAL) == static_cast<ssize_t>(s.size()); }

// reply_timeout_s bounded each read, not the reply: one byte every 50 ms held the odometry thread
// for the whole reply (5 s here, unbounded in general) with reply_timeouts 0.
TEST(RobotinoClient, TheReplyTimeoutIsADeadlineOnTheWholeRequest) {
  RawServer server([](int fd, const std::atomic<bool>& stop) {
    const std::string reply = "HTTP/1.1 200 OK\r\nContent-Type: application/json\r\nContent-Length: 100\r\n\r\n[" +
                              std::string(98, ' ') + "]";
    for (char c : reply) {
      if (stop || !send_all(fd, std::string(1, c))) return;
      std::this_thread::sleep_for(50ms);
    }
  });
  RobotinoClient client(server.url(), 1.0, 0.3);
  const int64_t t0 = monotonic_us();
  const Reply r = client.get("/data/odometry");
  const double took_s = static_cast<double>(monotonic_us() - t0) * 1e-6;
  EXPECT_EQ(r.status, ReplyStatus::kTimeout) << r.error;
  EXPECT_LT(took_s, 1.0) << "the request must end at its 0.3 s deadline";
  EXPECT_NE(r.error.find("no complete reply within 0.300 s"), std::string::npos) << r.error;
  EXPECT_EQ(client.deadlines_missed(), 1);
}

// based buffered a whole reply before its 4 KiB check (a 100 MB reply: RSS 12 → 277 MB). The cap now
// applies while reading: a reply that sends 8 KiB and then stalls is refused at once, not at the deadline.
TEST(RobotinoClient, AReplyBodyPastTheCapIsRefusedWhileItIsRead) {
  RawServer server([](int fd, const std::atomic<bool>& stop) {
    const std::string head = "HTTP/1.1 200 OK\r\nContent-Type: application/json\r\nContent-Length: 104857600\r\n\r\n";
    if (!send_all(fd, head) || !send_all(fd, std::string(8192, '1'))) return;
    while (!stop) std::this_thread::sleep_for(10ms);  // the other 100 MB never come
  });
  RobotinoClient client(server.url(), 1.0, 5.0);
  const int64_t t0 = monotonic_us();
  const Reply r = client.get("/data/odometry");
  const double took_s = static_cast<double>(monotonic_us() - t0) * 1e-6;
  EXPECT_EQ(r.status, ReplyStatus::kTooLarge) << r.error;
  EXPECT_LT(took_s, 2.0) << "refused at the 4,097th byte, not at the 5 s deadline";
  EXPECT_TRUE(r.body.empty());
  EXPECT_NE(r.error.find("larger than 4096 bytes"), std::string::npos) << r.error;
}

TEST(RobotinoClient, AnOrdinaryReplyStillComesThrough) {
  RawServer server([](int fd, const std::atomic<bool>&) {
    const std::string body = "[1, 2, 0.5, 0, 0, 0, 7]";
    send_all(fd, "HTTP/1.1 200 OK\r\nContent-Type: application/json\r\nContent-Length: " + std::to_string(body.size()) +
                     "\r\nConnection: close\r\n\r\n" + body);
  });
  RobotinoClient client(server.url(), 1.0, 1.0);
  const Reply r = client.get("/data/odometry");
  EXPECT_EQ(r.status, ReplyStatus::kOk) << r.error;
  EXPECT_EQ(r.body, "[1, 2, 0.5, 0, 0, 0, 7]");
  const Reply again = client.post("/data/omnidrive", "[0, 0, 0]");
  EXPECT_EQ(again.status, ReplyStatus::kOk) << again.error;
  EXPECT_EQ(client.deadlines_missed(), 0);
}

}  // namespace
}  // namespace whiskeye::based
