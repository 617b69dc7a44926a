// Six whisker boards in closed loop on a (v)CAN interface, for the VM scenario calibrate's live θ
// sweep: every 2 ms each whisker's joint moves toward the target its last motor command gave (at most
// 2 rad/s, only while its enable bit is set), stops at the end stops ±stop_deg, and the boards send
// their samples and heartbeats through sim::BoardTraffic with the true calibration vita-sim draws
// from --truth-seed (so the encoder counts are that robot's). --fault-at T sets board 0's fault bit
// from T s on. Runs --seconds, then exits 0.
//   board_sim_vm --interface vcan0 --truth-seed 5 [--stop-deg 60] [--seconds 40] [--fault-at T]
#include <CLI/CLI.hpp>
#include <time.h>

#include <algorithm>
#include <cmath>
#include <iostream>
#include <vector>

#include "whiskeye/can/can_socket.h"
#include "whiskeye/sim/bringup.h"
#include "whiskeye/sim/can_log.h"

using namespace whiskeye;

int main(int argc, char** argv) {
  CLI::App app("board_sim_vm");
  std::string interface = "vcan0";
  uint64_t seed = 5;
  double stop_deg = 60.0, seconds = 40.0, fault_at = -1.0;
  app.add_option("--interface", interface);
  app.add_option("--truth-seed", seed);
  app.add_option("--stop-deg", stop_deg);
  app.add_option("--seconds", seconds);
  app.add_option("--fault-at", fault_at);
  CLI11_PARSE(app, argc, argv);
  const sim::TrueCalibration truth = sim::draw_true_calibration(seed);
  sim::BoardTrafficParams tp;
  tp.calibration = truth.calibration;
  tp.channel = truth.channel;
  sim::BoardTraffic traffic(tp);
  can::Socket sock(interface);
  const double stop = stop_deg * kPi / 180.0;
  constexpr double kPeriod = 0.002, kMaxRate = 2.0;
  std::array<double, wp::kNumWhiskers> theta{}, target{};  // per whisker, rad
  uint32_t mask = 0;
  rcp::WhiskerSample s;
  sim::WhiskerHealth health;
  std::vector<sim::CanFrame> frames;
  can::Frame frame;
  timespec next{};
  clock_gettime(CLOCK_MONOTONIC, &next);
  int64_t sent = 0, commands = 0;
  const auto periods = static_cast<int64_t>(seconds / kPeriod);
  for (int64_t i = 0; i < periods; ++i) {
    // Every command received since the last period (FD: one broadcast frame for all 24 channels).
    while (sock.receive(frame, 0) == can::Socket::Rx::kFrame) {
      const wp::Decoded d = wp::decode_frame(frame.id, frame.fd, frame.payload(), wp::BusMode::kFd);
      if (d.kind != wp::FrameKind::kCommand) continue;
      ++commands;
      mask = d.command.enable_mask;
      for (int w = 0; w < wp::kNumWhiskers; ++w) {
        const int ch = truth.channel[static_cast<std::size_t>(w)];
        const wp::WhiskerCalibration& c = truth.calibration[static_cast<std::size_t>(w)];
        target[static_cast<std::size_t>(w)] = c.theta_gain * (d.command.theta_target[static_cast<std::size_t>(ch)] - c.theta_offset);
      }
    }
    const double t = static_cast<double>(i) * kPeriod;
    s.utime = 1700000000000000 + i * 2000;
    s.seq = i;
    for (int w = 0; w < wp::kNumWhiskers; ++w) {
      double& th = theta[static_cast<std::size_t>(w)];
      if (mask & (1u << truth.channel[static_cast<std::size_t>(w)])) {
        th += std::clamp(target[static_cast<std::size_t>(w)] - th, -kMaxRate * kPeriod, kMaxRate * kPeriod);
      }
      th = std::clamp(th, -stop, stop);
      s.theta[w] = th;
      s.valid[w] = true;
      health.fault[w] = fault_at >= 0 && t >= fault_at && w / wp::kWhiskersPerBoard == 0;
    }
    frames.clear();
    traffic.add(s, health, frames);
    for (const sim::CanFrame& f : frames) {
      can::Frame out;
      out.id = f.id;
      out.fd = f.fd;
      out.brs = f.fd;
      out.len = static_cast<uint8_t>(f.data.size());
      std::copy(f.data.begin(), f.data.end(), out.data.begin());
      sent += sock.send(out) ? 1 : 0;
    }
    next.tv_nsec += 2000000;
    if (next.tv_nsec >= 1000000000) {
      next.tv_nsec -= 1000000000;
      ++next.tv_sec;
    }
    clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &next, nullptr);
  }
  std::cout << "board_sim_vm: " << sent << " frames sent, " << commands << " commands received\n";
  return 0;
}
