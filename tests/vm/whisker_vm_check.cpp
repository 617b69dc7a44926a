// VM test program for whiskerd: emulates the six whisker boards on a (v)can interface at 500 Hz with
// scripted content — per-whisker values, sequence gaps on board 2, one frame of each bad kind, and a
// contact on whisker 5 — while listening to whiskerd's LCM output and its motor command frames, then
// reports one PASS/FAIL line per checked behaviour into the results file.
// --mode classic runs the same script on classic CAN (one frame per whisker, 100 Hz, per-board
// command frames without sequence numbers) and prefixes its test names with "classic_".
//   whisker_vm_check --interface vcan0 --results FILE [--mode fd|classic]
#include <linux/can.h>
#include <linux/can/error.h>
#include <linux/can/raw.h>
#include <net/if.h>
#include <sys/ioctl.h>
#include <sys/socket.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <cstdlib>
#include <cstring>
#include <atomic>
#include <cmath>
#include <fstream>
#include <iostream>
#include <map>
#include <mutex>
#include <thread>
#include <sched.h>
#include <time.h>

#include <whiskeye/common/bus.h>
#include <whiskeye/common/clock.h>
#include <whiskeye/driver_status_t.hpp>
#include <whiskeye/rcp_state_t.hpp>
#include <whiskeye/whisk_cycle_t.hpp>
#include <whiskeye/whisker_sample_t.hpp>

#include "whiskeye/can/can_socket.h"
#include "whiskeye/whisker_protocol/whisker_protocol.h"

using namespace whiskeye;

namespace {

// The script in samples; classic mode runs it at a fifth of the rate (same duration).
struct Script {
  bool classic = false;
  int samples = 1500;       // 3 s at 500 Hz
  int contact_from = 750;   // whisker 5 touches from here to the end
  int bad_at = 200;
  int bus_off_at = 400;     // an error frame says bus-off here ...
  int restart_at = 1100;    // ... and the controller restarted here
  int reboot_at = 600;      // board 4 reboots here: boot-up heartbeat, its seq starts over at 0
  long period_ns = 2000000;
  wp::BusMode mode() const { return classic ? wp::BusMode::kClassic : wp::BusMode::kFd; }
};
Script classic_script() {
  Script s;
  s.classic = true;
  s.samples = 300;
  s.contact_from = 150;
  s.bad_at = 40;
  s.bus_off_at = 80;
  s.restart_at = 220;
  s.reboot_at = 190;
  s.period_ns = 10000000;
  return s;
}
constexpr int kContactWhisker = 5;
constexpr int16_t kContactX = 1200;
constexpr double kThetaMax = 45.0 * M_PI / 180.0;

int16_t value_x(int w) { return static_cast<int16_t>(10 * (w / 4) + w % 4); }
int16_t value_theta(int w) { return static_cast<int16_t>(100 + 5 * w); }
// 6 lost samples; 270 is past the 8-bit classic sequence wrap.
bool board2_skips(int seq) { return (seq >= 100 && seq <= 104) || seq == 270; }
// Board 4 reboots at script.reboot_at. Before, its seq runs ahead of the others by an offset that
// puts it in the upper half of the sequence space at the reboot (FD 40599, classic 133), where the
// step back to 0 looks like a forward one: only its boot-up heartbeat keeps that out of the gaps.
constexpr int kRebootBoard = 4;
can::Frame heartbeat_frame(int board, uint8_t nmt_state) {
  can::Frame h;
  h.id = wp::heartbeat_id({}, board);
  h.len = static_cast<uint8_t>(wp::encode_heartbeat({board, nmt_state, 0}, h.data));
  return h;
}
int board_seq(int b, int seq, const Script& script) {
  if (b != kRebootBoard) return seq;
  return seq < script.reboot_at ? seq + (script.classic ? 200 : 40000) : seq - script.reboot_at;
}

struct Results {
  std::ofstream out;
  std::string prefix;
  int failures = 0;
  void report(const std::string& name, bool ok, const std::string& why = "") {
    out << (ok ? "PASS " : "FAIL ") << prefix << name << (ok ? "" : ": " + why) << "\n";
    std::cout << (ok ? "PASS " : "FAIL ") << prefix << name << (ok ? "" : ": " + why) << std::endl;
    if (!ok) ++failures;
  }
};

struct Received {
  std::mutex m;
  std::map<int64_t, whisker_sample_t> samples;  // by utime
  std::map<int64_t, rcp_state_t> states;        // by utime
  std::vector<driver_status_t> status;
  std::vector<whisk_cycle_t> cycles;
};

// Next sample time. Real boards never burst: after a stall of the emulated CPU the schedule restarts
// from now instead of sending the missed samples back to back.
void sleep_until(timespec& t, long add_ns) {
  t.tv_nsec += add_ns;
  while (t.tv_nsec >= 1000000000) {
    t.tv_nsec -= 1000000000;
    ++t.tv_sec;
  }
  timespec now;
  clock_gettime(CLOCK_MONOTONIC, &now);
  const int64_t behind_ns = (now.tv_sec - t.tv_sec) * 1000000000LL + (now.tv_nsec - t.tv_nsec);
  if (behind_ns > 10000000) {
    t = now;
    return;
  }
  while (clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &t, nullptr) == EINTR) {
  }
}

// The socket never blocks; a full send queue (a slow emulated CPU) is waited out, so the only lost
// samples are the scripted ones.
void send_reliably(can::Socket& sock, const can::Frame& f) {
  for (int attempt = 0; attempt < 20000 && !sock.send(f); ++attempt) {
    std::this_thread::sleep_for(std::chrono::microseconds(100));
  }
}

can::Frame fd_frame(uint32_t id, std::size_t len) {
  can::Frame f;
  f.id = id;
  f.fd = true;
  f.brs = true;
  f.len = static_cast<uint8_t>(len);
  return f;
}

// Writes a controller error frame onto the virtual bus, as a CAN driver would report it (vcan has
// no controller; raw sockets with an error mask receive it as an error frame).
bool inject_error_frame(const std::string& interface, uint32_t error_class) {
  const int fd = ::socket(PF_CAN, SOCK_RAW, CAN_RAW);
  if (fd < 0) return false;
  ifreq ifr{};
  std::strncpy(ifr.ifr_name, interface.c_str(), IFNAMSIZ - 1);
  sockaddr_can addr{};
  addr.can_family = AF_CAN;
  bool ok = ::ioctl(fd, SIOCGIFINDEX, &ifr) == 0;
  addr.can_ifindex = ifr.ifr_ifindex;
  ok = ok && ::bind(fd, reinterpret_cast<sockaddr*>(&addr), sizeof(addr)) == 0;
  can_frame f{};
  f.can_id = CAN_ERR_FLAG | error_class;
  f.can_dlc = CAN_ERR_DLC;
  ok = ok && ::write(fd, &f, sizeof(f)) == static_cast<ssize_t>(sizeof(f));
  ::close(fd);
  return ok;
}

}  // namespace

// The kernel tells a CAN socket once that its interface went down (a pending socket error); a send
// that comes before the next receive takes that report. can::Socket must still return kDown from the
// next receive, or whiskerd never reopens and only counts failing sends (a race on a loaded machine:
// the notification landing between a period's drain and its motor command). Once reopened while the
// interface is still down, neither the pending error of the bind nor failing sends may report it
// again (a reopen every period).
int socket_down_check(const std::string& interface, Results& results) {
  const auto link = [&](const char* state) {
    return std::system(("ip link set " + interface + " " + state).c_str()) == 0;
  };
  can::Frame f;
  f.id = 0x7ff;
  f.fd = true;
  f.len = 8;
  can::Socket sock(interface);
  results.report("socket_sends_while_up", sock.send(f));
  if (!link("down")) {
    results.report("socket_check_sets_link_down", false, "ip link set down failed");
    return 1;
  }
  results.report("socket_send_fails_while_down", !sock.send(f));  // takes the kernel's one report
  can::Frame in;
  const can::Socket::Rx after_send = sock.receive(in, 0);
  results.report("socket_receive_reports_down_after_a_send_took_the_report", after_send == can::Socket::Rx::kDown,
                 std::string("receive returned ") + std::to_string(static_cast<int>(after_send)) + ", last error: " +
                     sock.last_error());
  results.report("socket_reopens_on_a_down_interface", sock.reopen(), sock.last_error());
  // can-raw's bind on a down interface leaves ENETDOWN pending; the first receive must not take it
  // for news (whiskerd, which drains before it sends, would reopen every period).
  const can::Socket::Rx first = sock.receive(in, 0);
  results.report("socket_reopened_while_down_does_not_report_down_at_its_first_receive",
                 first != can::Socket::Rx::kDown, std::string("last error: ") + sock.last_error());
  sock.send(f);
  const can::Socket::Rx reopened = sock.receive(in, 0);
  results.report("socket_does_not_report_down_again_after_reopening", reopened != can::Socket::Rx::kDown,
                 "failing sends on the reopened socket reported the interface down again");
  link("up");
  results.report("socket_sends_again_after_up", sock.send(f), sock.last_error());
  results.report("socket_receives_after_up", sock.receive(in, 0) != can::Socket::Rx::kDown);
  return results.failures == 0 ? 0 : 1;
}

int main(int argc, char** argv) {
  CLI::App app{"whiskerd VM test: board emulator and output checker"};
  std::string interface = "vcan0", results_path, mode = "fd";
  bool socket_down = false;
  app.add_option("--interface", interface);
  app.add_option("--mode", mode)->check(CLI::IsMember({"fd", "classic"}));
  app.add_option("--results", results_path)->required();
  app.add_flag("--socket-down", socket_down, "only check can::Socket's report of the interface going down");
  CLI11_PARSE(app, argc, argv);
  if (socket_down) {
    Results results;
    results.out.open(results_path, std::ios::app);
    return socket_down_check(interface, results);
  }

  const Script script = mode == "classic" ? classic_script() : Script{};
  Results results;
  results.prefix = script.classic ? "classic_" : "";
  results.out.open(results_path, std::ios::app);
  Received rx;
  LcmBus bus;
  DecodeErrors errors;
  subscribe<whisker_sample_t>(bus, "WHISKER_SAMPLE", [&](const whisker_sample_t& m) {
    std::lock_guard lock(rx.m);
    rx.samples[m.utime] = m;
  }, errors);
  subscribe<rcp_state_t>(bus, "RCP_STATE", [&](const rcp_state_t& m) {
    std::lock_guard lock(rx.m);
    rx.states[m.utime] = m;
  }, errors);
  subscribe<driver_status_t>(bus, "DRIVER_STATUS", [&](const driver_status_t& m) {
    std::lock_guard lock(rx.m);
    rx.status.push_back(m);
  }, errors);
  subscribe<whisk_cycle_t>(bus, "WHISK_CYCLE", [&](const whisk_cycle_t& m) {
    std::lock_guard lock(rx.m);
    rx.cycles.push_back(m);
  }, errors);
  std::atomic<bool> done{false};
  std::thread lcm_thread([&] {
    while (!done) bus.handle_timeout(50);
  });

  can::Socket tx(interface);
  can::Socket motor(interface);
  motor.set_filters({{0x200, 0x7f8}});
  std::map<uint16_t, wp::MotorCommand> commands;  // FD: by command seq
  std::vector<uint16_t> command_order;
  std::array<std::vector<wp::MotorCommand>, wp::kNumBoards> board_commands;  // classic: per board, in order
  int bad_commands = 0;
  int64_t timestamp_errors = 0, timestamped = 0;
  std::thread motor_thread([&] {
    can::Frame f;
    while (!done) {
      if (motor.receive(f, 50000) != can::Socket::Rx::kFrame) continue;
      const wp::Decoded d = wp::decode_frame(f.id, f.fd, f.payload(), script.mode());
      std::lock_guard lock(rx.m);
      ++timestamped;
      if (std::llabs(now_utime() - f.rx_utime) > 1000000) ++timestamp_errors;
      if (d.kind != wp::FrameKind::kCommand) {
        ++bad_commands;
        continue;
      }
      if (script.classic) {
        board_commands[d.command_board].push_back(d.command);
      } else {
        commands[d.command.seq] = d.command;
        command_order.push_back(d.command.seq);
      }
    }
  });

  // Wait for whiskerd to be up (it publishes every period even before the boards stream).
  for (int i = 0; i < 600; ++i) {
    {
      std::lock_guard lock(rx.m);
      if (!rx.states.empty()) break;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }

  // --- board emulation ---
  // One CPU for the sender: vcan hands frames to the backlog of the CPU that sent them, so a sender
  // migrating between CPUs could reorder frames, which no real CAN controller does.
  cpu_set_t one_cpu;
  CPU_ZERO(&one_cpu);
  CPU_SET(0, &one_cpu);
  if (sched_setaffinity(0, sizeof(one_cpu), &one_cpu) != 0) std::cout << "cannot pin the emulator" << std::endl;
  timespec t;
  clock_gettime(CLOCK_MONOTONIC, &t);
  int64_t contact_onset_mono = 0;
  for (int seq = 0; seq < script.samples; ++seq) {
    if (seq == script.reboot_at) send_reliably(tx, heartbeat_frame(kRebootBoard, wp::kNmtBootUp));
    for (int b = 0; b < wp::kNumBoards; ++b) {
      if (b == 2 && board2_skips(seq)) continue;
      wp::BoardSample s;
      s.board = b;
      s.seq = static_cast<uint16_t>(board_seq(b, seq, script));
      for (int k = 0; k < 4; ++k) {
        const int w = 4 * b + k;
        s.whiskers[k].x = (w == kContactWhisker && seq >= script.contact_from) ? kContactX : value_x(w);
        s.whiskers[k].y = static_cast<int16_t>(-value_x(w));
        s.whiskers[k].theta = value_theta(w);
      }
      if (script.classic) {
        for (int k = 0; k < 4; ++k) {
          can::Frame f;
          f.id = wp::sample_id({}, b);
          f.len = static_cast<uint8_t>(
              wp::encode_fragment({b, static_cast<uint8_t>(s.seq & 0xff), k, 0, s.whiskers[k]}, f.data));
          send_reliably(tx, f);
        }
      } else {
        can::Frame f = fd_frame(wp::sample_id({}, b), wp::kFdSampleBytes);
        wp::encode_sample_fd(s, f.data);
        send_reliably(tx, f);
      }
    }
    if (seq == script.contact_from) contact_onset_mono = monotonic_us();
    if (seq % (script.classic ? 10 : 50) == 0) {
      for (int b = 0; b < wp::kNumBoards; ++b) send_reliably(tx, heartbeat_frame(b, 0x05));
    }
    if (seq == script.bus_off_at && !inject_error_frame(interface, CAN_ERR_BUSOFF)) std::cout << "cannot inject bus-off" << std::endl;
    if (seq == script.restart_at && !inject_error_frame(interface, CAN_ERR_RESTARTED)) std::cout << "cannot inject restart" << std::endl;
    if (seq == script.bad_at) {
      // Frames whose 11 low id bits name board 0's sample but that are no sample: a CANopen tool's
      // remote request (a DLC of 8, no data) and an extended-id frame with a sample's payload
      // (out of range, so a decoder taking it would count it). The kernel filters keep both out.
      can::Frame rtr;
      rtr.id = wp::sample_id({}, 0);
      rtr.rtr = true;
      rtr.len = 8;
      send_reliably(tx, rtr);
      wp::WhiskerRaw bad;
      bad.x = 3000;
      can::Frame ext = script.classic ? can::Frame{} : fd_frame(wp::sample_id({}, 0), 32);
      ext.id = wp::sample_id({}, 0);
      ext.extended = true;
      if (script.classic) {
        ext.len = static_cast<uint8_t>(wp::encode_fragment({0, 0x55, 0, 0, bad}, ext.data));
      } else {
        wp::BoardSample s;
        s.whiskers[0] = bad;
        wp::encode_sample_fd(s, ext.data);
      }
      send_reliably(tx, ext);
    }
    if (seq == script.bad_at && script.classic) {
      can::Frame f;
      f.id = 0x181;
      f.len = 5;  // wrong length
      send_reliably(tx, f);
      f.id = 0x187;  // node 7 does not exist
      f.len = 8;
      send_reliably(tx, f);
      wp::WhiskerRaw bad;
      bad.x = 3000;  // beyond the 12-bit ADC
      f.id = 0x184;
      f.len = static_cast<uint8_t>(wp::encode_fragment({3, 0x55, 0, 0, bad}, f.data));
      send_reliably(tx, f);
    } else if (seq == script.bad_at) {
      can::Frame f = fd_frame(0x181, 20);  // wrong length
      send_reliably(tx, f);
      f = fd_frame(0x187, 32);  // node 7 does not exist
      send_reliably(tx, f);
      wp::BoardSample s;
      s.board = 3;
      s.seq = 9999;
      s.whiskers[0].x = 3000;  // beyond the 12-bit ADC
      f = fd_frame(0x184, 32);
      wp::encode_sample_fd(s, f.data);
      send_reliably(tx, f);
    }
    if (seq == script.bad_at) {
      // A sample of the other frame type (an FD board on a bus configured classic, or the reverse):
      // counted as such. The kernel dropped FD frames unseen on a socket without FD frames enabled.
      can::Frame f = script.classic ? fd_frame(wp::sample_id({}, 1), wp::kFdSampleBytes) : can::Frame{};
      f.id = wp::sample_id({}, 1);
      if (!script.classic) f.len = 8;
      send_reliably(tx, f);
    }
    sleep_until(t, script.period_ns);
  }
  (void)contact_onset_mono;
  std::cout << "emulator: " << tx.counters().tx_frames << " frames sent, " << tx.counters().tx_errors
            << " send retries" << std::endl;
  // Silence: whiskerd must see a stale bus, retract and drop enable.
  std::this_thread::sleep_for(std::chrono::milliseconds(2500));
  done = true;
  lcm_thread.join();
  motor_thread.join();

  std::lock_guard lock(rx.m);
  const std::size_t min_periods = script.classic ? 100 : 500;
  results.report("whiskerd_publishes_samples_and_states", rx.samples.size() > min_periods && rx.states.size() > min_periods,
                 std::to_string(rx.samples.size()) + " samples, " + std::to_string(rx.states.size()) + " states");

  // Decoded and calibrated values in a sample where every board was fresh and before the contact.
  bool found = false, values_ok = true;
  std::string why;
  for (const auto& [utime, m] : rx.samples) {
    bool fresh = m.num_whiskers == 24;
    for (int w = 0; fresh && w < 24; ++w) fresh = m.status[w] == 0;
    if (!fresh || m.raw_x[kContactWhisker] == kContactX) continue;
    found = true;
    for (int w = 0; w < 24; ++w) {
      if (m.raw_x[w] != value_x(w) || m.raw_y[w] != -value_x(w) || m.raw_theta[w] != value_theta(w)) {
        values_ok = false;
        why = "raw values of whisker " + std::to_string(w);
      }
      const double theta = value_theta(w) * 2 * M_PI / 4096;
      if (std::abs(m.theta[w] - theta) > 1e-5) {
        values_ok = false;
        why = "theta of whisker " + std::to_string(w);
      }
    }
    // config: whisker 23 offset_x 50, gain_x 0.0009; whisker 22 rotated by 90 deg.
    if (std::abs(m.deflection_x[23] - 0.0009 * (value_x(23) - 50)) > 1e-6 ||
        std::abs(m.deflection_y[23] + value_x(23) / 2047.0) > 1e-6) {
      values_ok = false;
      why = "calibration offset/gain of whisker 23";
    }
    if (std::abs(m.deflection_x[22] - value_x(22) / 2047.0) > 1e-6 ||
        std::abs(m.deflection_y[22] - value_x(22) / 2047.0) > 1e-6) {
      values_ok = false;
      why = "calibration rotation of whisker 22: " + std::to_string(m.deflection_x[22]) + "," +
            std::to_string(m.deflection_y[22]);
    }
    if (std::abs(m.deflection_x[0] - value_x(0) / 2047.0) > 1e-6) {
      values_ok = false;
      why = "default calibration of whisker 0";
    }
    break;
  }
  results.report("whiskerd_decodes_and_calibrates_whisker_values", found && values_ok,
                 found ? why : "no sample with every board fresh");

  // Counters in the last DRIVER_STATUS.
  std::map<std::string, int64_t> counters;
  int8_t last_state = -1;
  std::string last_message;
  if (!rx.status.empty()) {
    const auto& s = rx.status.back();
    for (int i = 0; i < s.num_counters; ++i) counters[s.counter_names[i]] = s.counter_values[i];
    last_state = s.state;
    last_message = s.message;
    std::cout << "DRIVER_STATUS stats:";
    for (const auto& st : rx.status) {
      for (int i = 0; i < st.num_stats; ++i) {
        if (st.stat_names[i].find("p99") != std::string::npos || st.stat_names[i].find("max") != std::string::npos) {
          std::cout << " " << st.stat_names[i] << "=" << st.stat_values[i];
        }
      }
      std::cout << " |";
    }
    std::cout << std::endl;
  }
  results.report("driver_status_published", rx.status.size() >= 3, std::to_string(rx.status.size()) + " messages");
  auto counter_is = [&](const std::string& name, int64_t want) {
    const auto it = counters.find(name);
    const int64_t got = it == counters.end() ? -1 : it->second;
    results.report("counter_" + name + "_is_" + std::to_string(want), got == want,
                   "got " + std::to_string(got) + " (kernel rx queue overflows: " +
                       std::to_string(counters.count("can_rx_overflow") ? counters["can_rx_overflow"] : -1) +
                       ", late samples: " + std::to_string(counters.count("late_samples") ? counters["late_samples"] : -1) + ")");
  };
  counter_is("gaps_board2", 6);
  counter_is("gaps_board0", 0);
  counter_is("gaps_board4", 0);  // its reboot is no loss
  counter_is("board_resyncs", 1);
  counter_is("gaps", 6);
  counter_is("rejected_wrong_length", 1);
  counter_is("rejected_unknown_id", 1);
  counter_is("rejected_out_of_range", 1);
  counter_is("rejected_wrong_frame_type", 1);

  // Bus-off reported (DEGRADED, "bus-off") and recovered from (later: running, error-active) while
  // whiskerd keeps running.
  std::size_t busoff_at = rx.status.size();
  for (std::size_t i = 0; i < rx.status.size(); ++i) {
    if (rx.status[i].message.find("bus-off") != std::string::npos &&
        rx.status[i].state == driver_status_t::STATE_DEGRADED) {
      busoff_at = i;
      break;
    }
  }
  bool recovered = false;
  for (std::size_t i = busoff_at + 1; i < rx.status.size(); ++i) {
    if (rx.status[i].message.find("running; bus error-active") != std::string::npos) recovered = true;
  }
  results.report("bus_off_is_reported_in_driver_status", busoff_at < rx.status.size(),
                 "no DEGRADED status mentioning bus-off");
  results.report("bus_off_recovers_without_restart", recovered, "no running/error-active status after bus-off");
  counter_is("can_bus_off", 1);
  counter_is("can_error_frames", 2);

  // Kernel receive timestamps on the frames the checker's own socket received.
  results.report("kernel_receive_timestamps_are_epoch_utime", timestamped > 0 && timestamp_errors == 0,
                 std::to_string(timestamp_errors) + " of " + std::to_string(timestamped) + " off by > 1 s");

  // WHISK_CYCLE at each cycle end (1 Hz whisking; the boards stream for 3 s).
  bool cycle_ok = !rx.cycles.empty();
  for (const auto& c : rx.cycles) {
    // Sample counts depend on how many periods an emulated, shared CPU managed; the structure does not.
    bool increasing = true;
    for (std::size_t i = 1; i < c.sample_utime.size(); ++i) increasing = increasing && c.sample_utime[i] > c.sample_utime[i - 1];
    cycle_ok = cycle_ok && c.num_whiskers == 24 && c.num_samples >= 10 &&
               static_cast<int>(c.sample_utime.size()) == c.num_samples && static_cast<int>(c.theta.size()) == c.num_samples &&
               c.utime_end > c.utime_start && increasing;
  }
  results.report("whisk_cycle_published_at_cycle_end", cycle_ok,
                 std::to_string(rx.cycles.size()) + " cycles" +
                     (rx.cycles.empty() ? "" : ", first has " + std::to_string(rx.cycles[0].num_samples) + " samples"));

  // Motor command frames.
  if (script.classic) {
    std::size_t frames = 0, boards_seen = 0, enabled_frames = 0, boards_disabled_at_end = 0;
    for (int b = 0; b < wp::kNumBoards; ++b) {
      const auto& v = board_commands[b];
      frames += v.size();
      boards_seen += !v.empty();
      const uint32_t board_mask = 0xFu << (4 * b);
      for (const auto& c : v) enabled_frames += (c.enable_mask & board_mask) == board_mask;
      boards_disabled_at_end += !v.empty() && (v.back().enable_mask & board_mask) == 0;
    }
    results.report("motor_command_frames_are_valid_classic_commands_for_every_board",
                   boards_seen == wp::kNumBoards && frames > 6 * min_periods && bad_commands == 0,
                   std::to_string(frames) + " frames from " + std::to_string(boards_seen) + " boards, " +
                       std::to_string(bad_commands) + " invalid");
    results.report("motor_commands_enable_all_whiskers_while_running", enabled_frames > 6 * 50,
                   std::to_string(enabled_frames) + " fully enabled frames");
    results.report("stale_bus_drops_enable", boards_disabled_at_end == wp::kNumBoards &&
                                                last_state != driver_status_t::STATE_OK &&
                                                last_message.find("stale") != std::string::npos,
                   std::to_string(boards_disabled_at_end) + " boards disabled at the end, status '" + last_message + "'");
  } else {
    results.report("motor_command_frames_are_valid_fd_commands", commands.size() > 500 && bad_commands == 0,
                   std::to_string(commands.size()) + " commands, " + std::to_string(bad_commands) + " invalid");
    int enabled_frames = 0;
    for (const auto& [seq, c] : commands) enabled_frames += c.enable_mask == 0xFFFFFF;
    results.report("motor_commands_enable_all_whiskers_while_running", enabled_frames > 300,
                   std::to_string(enabled_frames) + " fully enabled frames");
    const bool last_disabled = !command_order.empty() && commands[command_order.back()].enable_mask == 0;
    results.report("stale_bus_drops_enable", last_disabled && last_state != driver_status_t::STATE_OK &&
                                                last_message.find("stale") != std::string::npos,
                   "last mask " + (command_order.empty() ? std::string("none") : std::to_string(commands[command_order.back()].enable_mask)) +
                       ", status '" + last_message + "'");
  }

  // Contact: every period that sees whisker 5 touching while protracting has the RCP ceiling lowered
  // and a command that does not rise; the reaction (a falling command, or the command already down at
  // the ceiling) is seen; in FD mode that period's own motor frame carries exactly that command.
  // (A period whose LCM messages were lost on a loaded emulator is skipped, never guessed.)
  int periods_checked = 0, frames_checked = 0;
  bool reaction = false, rcp_ok = true;
  std::string rcp_why;
  const rcp_state_t* prev_state = nullptr;
  int64_t prev_seq = -1;
  for (const auto& [utime, m] : rx.samples) {
    const auto st = rx.states.find(utime);
    if (st == rx.states.end()) {
      prev_state = nullptr;
      continue;
    }
    const rcp_state_t& r = st->second;
    const bool touching = m.raw_x[kContactWhisker] == kContactX && m.status[kContactWhisker] == 0;
    if (touching && r.phase == rcp_state_t::PHASE_PROTRACT && r.enabled && prev_state != nullptr && prev_seq == m.seq - 1) {
      ++periods_checked;
      const float cmd = r.theta_command[kContactWhisker], ceiling = r.theta_ceiling[kContactWhisker];
      const float prev_cmd = prev_state->theta_command[kContactWhisker];
      if (!(ceiling < kThetaMax - 0.1) || cmd > prev_cmd + 1e-6f) {
        rcp_ok = false;
        rcp_why = "seq " + std::to_string(m.seq) + ": ceiling " + std::to_string(ceiling) + " command " +
                  std::to_string(cmd) + " previous " + std::to_string(prev_cmd);
      }
      reaction = reaction || cmd < prev_cmd || std::abs(cmd - ceiling) < 1e-4f;
      if (!script.classic) {
        const auto frame = commands.find(static_cast<uint16_t>(m.seq & 0xffff));
        const auto prev_frame = commands.find(static_cast<uint16_t>((m.seq - 1) & 0xffff));
        if (frame != commands.end() && prev_frame != commands.end()) {
          ++frames_checked;
          const int16_t target = frame->second.theta_target[kContactWhisker];
          const int16_t expected = static_cast<int16_t>(std::lround(cmd * 4096 / (2 * M_PI)));
          if (target != expected || target > prev_frame->second.theta_target[kContactWhisker]) {
            rcp_ok = false;
            rcp_why = "seq " + std::to_string(m.seq) + ": motor frame target " + std::to_string(target) +
                      ", expected " + std::to_string(expected) + ", previous frame " +
                      std::to_string(prev_frame->second.theta_target[kContactWhisker]);
          }
        }
      }
    }
    prev_state = &r;
    prev_seq = m.seq;
  }
  const bool contact_seen = periods_checked > 0 && reaction && (script.classic || frames_checked > 0);
  if (rcp_ok && !contact_seen) {
    rcp_why = std::to_string(periods_checked) + " touching protraction periods, " + std::to_string(frames_checked) +
              " with motor frames, reaction " + (reaction ? "seen" : "not seen");
  }
  std::cout << "contact check: " << periods_checked << " periods, " << frames_checked << " motor frames; " << rcp_why
            << std::endl;
  results.report(script.classic ? "contact_lowers_rcp_ceiling_in_the_same_period"
                                 : "contact_lowers_rcp_ceiling_in_the_next_motor_frame",
                 contact_seen && rcp_ok, rcp_why);
  return results.failures == 0 ? 0 : 1;
}
