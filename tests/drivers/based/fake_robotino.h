// A Robotino REST server for tests, on 127.0.0.1 and a free port: GET /data/odometry and
// POST /data/omnidrive as documented, with faults scripted per reply. The simulated base moves at a
// constant body velocity; the pose of sample `seq` is a pure function of seq (expected_pose), so tests
// can check every published value exactly.
#pragma once

#include <chrono>
#include <cstdint>
#include <deque>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

namespace httplib {
class Server;
}

namespace whiskeye::based::testing {

enum class Fault {
  kSlow,          // reply after slow_reply_ms (beyond the client's timeout)
  kMalformed,     // "[1, 2, oops"
  kWrongLength,   // three elements
  kNaN,           // a NaN literal (not JSON)
  kNull,          // null where a number belongs (what JSON writers emit for NaN)
  kHttp500,       // status 500
  kDrop,          // headers sent, then the connection is closed before the body
  kRepeatSeq,     // the previous sample again
  kJump,          // the base's odometry origin moves by 5 m from now on
  kSeqRestart,    // the base restarts: seq starts again from 1000 lower
};

struct ReceivedCommand {
  int64_t mono_us = 0;
  double vx = 0.0;
  double vy = 0.0;
  double omega = 0.0;
};

struct FakePose {
  double x, y, theta, vx, vy, omega;
};

class FakeRobotino {
 public:
  // port 0: any free port. keep_alive_max: requests the server serves on one connection before
  // closing it (servers do this; the client must reconnect without counting a fault).
  explicit FakeRobotino(int port = 0, int keep_alive_max = 1000000);
  ~FakeRobotino();
  FakeRobotino(const FakeRobotino&) = delete;
  FakeRobotino& operator=(const FakeRobotino&) = delete;

  int port() const { return port_; }
  std::string url() const { return "http://127.0.0.1:" + std::to_string(port_); }

  // Faults for the next odometry replies, in order (then normal replies again).
  void script(const std::vector<Fault>& faults);
  void set_slow_reply_ms(int ms) { slow_ms_ = ms; }
  // Every reply waits this long before and after taking the sample (for the mid-round-trip check).
  void set_reply_delay_ms(int ms) { delay_ms_ = ms; }

  // The pose the simulated base reports for a sample (before any scripted jump).
  static FakePose expected_pose(int64_t seq);
  static constexpr int64_t kFirstSeq = 5000;

  std::vector<ReceivedCommand> commands() const;
  int64_t odometry_requests() const;
  // Wall-clock time at which sample `seq` was taken (0 if unknown).
  int64_t sample_utime(int64_t seq) const;

 private:
  std::string odometry_body();

  std::unique_ptr<httplib::Server> server_;
  std::thread thread_;
  int port_ = 0;
  int slow_ms_ = 150;
  int delay_ms_ = 0;
  mutable std::mutex mutex_;
  std::deque<Fault> script_;
  std::vector<ReceivedCommand> commands_;
  std::vector<std::pair<int64_t, int64_t>> sample_times_;  // (seq, utime)
  int64_t requests_ = 0;
  int64_t seq_ = kFirstSeq - 1;
  int64_t seq_shift_ = 0;
  double x_shift_ = 0.0;
};

}  // namespace whiskeye::based::testing
