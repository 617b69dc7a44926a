// The test's Robotino REST server (see fake_robotino.h).
#include "fake_robotino.h"

#include "whiskeye/common/clock.h"
#include "whiskeye/common/se2.h"

#include <httplib.h>
#include <nlohmann/json.hpp>

#include <stdexcept>

namespace whiskeye::based::testing {

FakePose FakeRobotino::expected_pose(int64_t seq) {
  // 10 ms per sample at vx 0.2, vy 0.1 m/s, omega 0.5 rad/s, starting at theta 3.0 so that theta
  // crosses pi and must be wrapped.
  const double vx = 0.2, vy = 0.1, omega = 0.5;
  const double t = 0.01 * static_cast<double>(seq - kFirstSeq);
  const Pose2 p = integrate_body_velocity(Pose2{1.0, -2.0, 3.0}, vx, vy, omega, t);
  // Report theta unwrapped, as a base integrating its heading would.
  return FakePose{p.x, p.y, 3.0 + omega * t, vx, vy, omega};
}

FakeRobotino::FakeRobotino(int port, int keep_alive_max) : server_(std::make_unique<httplib::Server>()) {
  server_->set_keep_alive_max_count(static_cast<size_t>(keep_alive_max));
  server_->set_tcp_nodelay(true);  // headers and body go out in separate writes: no Nagle wait
  server_->Get("/data/odometry", [this](const httplib::Request&, httplib::Response& res) {
    Fault fault{};
    bool faulty = false;
    {
      std::lock_guard<std::mutex> lock(mutex_);
      ++requests_;
      if (!script_.empty()) {
        fault = script_.front();
        script_.pop_front();
        faulty = true;
      }
    }
    if (delay_ms_ > 0) std::this_thread::sleep_for(std::chrono::milliseconds(delay_ms_));
    std::string body;
    if (faulty) {
      switch (fault) {
        case Fault::kSlow:
          std::this_thread::sleep_for(std::chrono::milliseconds(slow_ms_));
          body = odometry_body();
          break;
        case Fault::kMalformed: body = "[1, 2, oops"; break;
        case Fault::kWrongLength: body = "[1.0, 2.0, 3.0]"; break;
        case Fault::kNaN: body = "[NaN, 0, 0, 0, 0, 0, 1]"; break;
        case Fault::kNull: body = "[0, 0, null, 0, 0, 0, 1]"; break;
        case Fault::kHttp500:
          res.status = 500;
          res.set_content("internal error", "text/plain");
          return;
        case Fault::kDrop:
          res.set_content_provider(
              100, "application/json", [](size_t, size_t, httplib::DataSink&) { return false; });
          return;
        case Fault::kRepeatSeq: {
          std::lock_guard<std::mutex> lock(mutex_);
          --seq_;
        }
          body = odometry_body();
          break;
        case Fault::kJump: {
          std::lock_guard<std::mutex> lock(mutex_);
          x_shift_ += 5.0;
        }
          body = odometry_body();
          break;
        case Fault::kSeqRestart: {
          std::lock_guard<std::mutex> lock(mutex_);
          seq_shift_ -= 1000;
        }
          body = odometry_body();
          break;
      }
    } else {
      body = odometry_body();
    }
    if (delay_ms_ > 0) std::this_thread::sleep_for(std::chrono::milliseconds(delay_ms_));
    res.set_content(body, "application/json");
  });
  server_->Post("/data/omnidrive", [this](const httplib::Request& req, httplib::Response& res) {
    const nlohmann::json j = nlohmann::json::parse(req.body, nullptr, false);
    if (j.is_discarded() || !j.is_array() || j.size() != 3 || !j[0].is_number() || !j[1].is_number() ||
        !j[2].is_number()) {
      res.status = 400;  // a real base rejects it; the test sees it as a command failure
      return;
    }
    std::lock_guard<std::mutex> lock(mutex_);
    commands_.push_back(ReceivedCommand{monotonic_us(), j[0].get<double>(), j[1].get<double>(), j[2].get<double>()});
    res.set_content("", "application/json");
  });
  if (port == 0) {
    port_ = server_->bind_to_any_port("127.0.0.1");
  } else {
    port_ = server_->bind_to_port("127.0.0.1", port) ? port : -1;
  }
  if (port_ <= 0) throw std::runtime_error("FakeRobotino: cannot bind 127.0.0.1");
  thread_ = std::thread([this] { server_->listen_after_bind(); });
  // stop() before the accept loop runs would be lost and the destructor would hang.
  while (!server_->is_running()) std::this_thread::sleep_for(std::chrono::milliseconds(1));
}

FakeRobotino::~FakeRobotino() {
  server_->stop();
  thread_.join();
}

std::string FakeRobotino::odometry_body() {
  std::lock_guard<std::mutex> lock(mutex_);
  ++seq_;
  const FakePose p = expected_pose(seq_);
  sample_times_.emplace_back(seq_ + seq_shift_, now_utime());
  return nlohmann::json::array({p.x + x_shift_, p.y, p.theta, p.vx, p.vy, p.omega, seq_ + seq_shift_}).dump();
}

void FakeRobotino::script(const std::vector<Fault>& faults) {
  std::lock_guard<std::mutex> lock(mutex_);
  script_.insert(script_.end(), faults.begin(), faults.end());
}

std::vector<ReceivedCommand> FakeRobotino::commands() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return commands_;
}

int64_t FakeRobotino::odometry_requests() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return requests_;
}

int64_t FakeRobotino::sample_utime(int64_t seq) const {
  std::lock_guard<std::mutex> lock(mutex_);
  for (auto it = sample_times_.rbegin(); it != sample_times_.rend(); ++it) {
    if (it->first == seq) return it->second;
  }
  return 0;
}

}  // namespace whiskeye::based::testing
