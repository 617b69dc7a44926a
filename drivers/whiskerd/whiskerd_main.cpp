// whiskerd: the whisker head daemon. A real-time control thread (SCHED_FIFO + mlockall when
// permitted) runs at the sample rate on absolute clock_nanosleep deadlines: drain CAN frames ->
// WhiskerCore::step -> motor command on the bus -> hand the period's messages to the publisher
// thread through a lock-free ring. Only the publisher thread touches LCM, so a slow or failing LCM
// never delays the control loop; it also reopens a CAN socket that went down (socket_custody.h).
// SIGTERM / SIGINT retract the whiskers and drop the enable line.
#include <pthread.h>
#include <sched.h>
#include <signal.h>
#include <sys/mman.h>
#include <time.h>

#include <CLI/CLI.hpp>
#include <atomic>
#include <cerrno>
#include <array>
#include <cstdarg>
#include <cstdio>
#include <cstring>
#include <iostream>
#include <memory>
#include <thread>
#include <variant>

#include <whiskeye/common/bus.h>
#include <whiskeye/common/cli.h>
#include <whiskeye/common/clock.h>
#include <whiskeye/common/log.h>
#include <whiskeye/common/service.h>
#include <whiskeye/driver_status_t.hpp>
#include <whiskeye/rcp_state_t.hpp>
#include <whiskeye/whisk_cycle_t.hpp>
#include <whiskeye/whisker_sample_t.hpp>

#include "whiskeye/common/socket_custody.h"
#include "whiskeye/common/spsc_ring.h"
#include "whiskeye/whiskerd/whiskerd_core.h"
#include "whiskeye/drivers/can_socket.h"

namespace {

using namespace whiskeye;
using namespace whiskeye::whiskerd;

std::atomic<bool> g_stop{false};
void on_signal(int) { g_stop.store(true); }

// One item handed from the control thread to the publisher thread. Log lines travel the same way so
// the control thread never blocks on stderr (a full journald pipe).
struct Item {
  enum class Kind { kNone, kPeriod, kStatus, kLog } kind = Kind::kNone;
  PeriodOutput period;
  StatusSnapshot status;
  std::array<char, 192> text{};
  LogLevel level = LogLevel::kInfo;  // of a kLog item
};
using Ring = SpscRing<Item, 256>;

int64_t timespec_us(const timespec& t) { return static_cast<int64_t>(t.tv_sec) * 1000000 + t.tv_nsec / 1000; }
int64_t mono_now_us() {
  timespec t;
  clock_gettime(CLOCK_MONOTONIC, &t);
  return timespec_us(t);
}
void add_ns(timespec& t, int64_t ns) {
  t.tv_nsec += ns;
  while (t.tv_nsec >= 1000000000) {
    t.tv_nsec -= 1000000000;
    ++t.tv_sec;
  }
}

// Real-time scheduling for the calling thread; false (with a warning) when not permitted.
bool make_realtime(const Params& p) {
  bool ok = true;
  if (p.lock_memory && mlockall(MCL_CURRENT | MCL_FUTURE) != 0) {
    log_warning(std::string("whiskerd: warning: mlockall failed (") + std::strerror(errno) +
                "); page faults may delay the control loop (needs CAP_IPC_LOCK or LimitMEMLOCK)");
    ok = false;
  }
  sched_param sp{};
  sp.sched_priority = p.rt_priority;
  if (const int e = pthread_setschedparam(pthread_self(), SCHED_FIFO, &sp); e != 0) {
    log_warning("whiskerd: warning: SCHED_FIFO priority " + std::to_string(p.rt_priority) + " not permitted (" +
                std::strerror(e) + "); running the control loop with normal scheduling, expect jitter");
    ok = false;
  }
  if (p.rt_cpu >= 0) {
    cpu_set_t set;
    CPU_ZERO(&set);
    CPU_SET(p.rt_cpu, &set);
    if (const int e = pthread_setaffinity_np(pthread_self(), sizeof(set), &set); e != 0) {
      log_warning("whiskerd: warning: cannot pin the control thread to CPU " + std::to_string(p.rt_cpu) + " (" +
                  std::strerror(e) + ")");
    }
  }
  return ok;
}

void send_command(can::Socket& sock, const Params& p, const wp::MotorCommand& cmd, WhiskerCore& core) {
  can::Frame f;
  if (p.mode == wp::BusMode::kFd) {
    f.fd = true;
    f.brs = true;
    f.id = wp::command_id(p.ids);
    f.len = static_cast<uint8_t>(wp::encode_command_fd(cmd, f.data));
    if (!sock.send(f)) ++core.counters()[Counters::kCanTxErrors];
    return;
  }
  for (int b = 0; b < wp::kNumBoards; ++b) {
    f.id = wp::command_board_id(p.ids, b);
    f.len = static_cast<uint8_t>(wp::encode_command_classic(cmd, b, f.data));
    if (!sock.send(f)) ++core.counters()[Counters::kCanTxErrors];
  }
}

// Drops the enable line and sends the boards a disabled command. Never throws: a second failure
// while shutting down must not end in std::terminate with the line high. Returns "" or why the
// line could not be dropped (the boards' disabled command went out regardless).
std::string disable_motors(gpio::MotorLines& lines, can::Socket* sock, const Params& p, WhiskerCore& core) {
  std::string error;
  try {
    lines.set_enable(false);
  } catch (const std::exception& e) {
    error = e.what();
  }
  if (sock != nullptr && sock->is_open()) {
    wp::MotorCommand off;
    send_command(*sock, p, off, core);
  }
  return error;
}

struct Shared {
  Ring ring;
  // Published whisk cycles travel back to the control thread, which recycles their storage: the
  // real-time loop then never allocates at a cycle completion. A full ring frees the cycle here.
  SpscRing<std::unique_ptr<rcp::WhiskCycle>, 8> used_cycles;
  // A CAN socket that went down is reopened by the publisher thread, not in the control loop.
  SocketCustody<can::Socket> can_socket;
  std::atomic<int64_t> rt_periods{0};
  std::atomic<bool> rt_done{false};
  std::atomic<int> exit_code{0};
};

// printf-style log line from the control thread: formatted into a fixed buffer, no allocation. The
// publisher thread writes it at `level` (common/log.h).
void rt_log(Shared& shared, LogLevel level, const char* fmt, ...) __attribute__((format(printf, 3, 4)));
void rt_log(Shared& shared, LogLevel level, const char* fmt, ...) {
  static Item item;  // only the control thread logs; reused to avoid a 6 kB stack object per call
  item.kind = Item::Kind::kLog;
  item.level = level;
  va_list args;
  va_start(args, fmt);
  std::vsnprintf(item.text.data(), item.text.size(), fmt, args);
  va_end(args);
  shared.ring.try_push(item);  // a full ring loses the line, never blocks
}

void control_thread(const Params& p, std::unique_ptr<can::Socket> sock, gpio::MotorLines& lines, Shared& shared,
                    ServiceNotifier& service) {
  const bool rt = make_realtime(p);
  WhiskerCore core(p);
  const int64_t period_ns = static_cast<int64_t>(1e9 / p.rate_hz);
  const int64_t period_us = period_ns / 1000;
  const int per_status = std::max(1, static_cast<int>(p.status_period_s * p.rate_hz));
  const int64_t status_period_us = static_cast<int64_t>(p.status_period_s * 1e6);
  int64_t next_status_mono = mono_now_us() + status_period_us;
  LatencyStats wake(static_cast<std::size_t>(per_status) + 16), loop(static_cast<std::size_t>(per_status) + 16),
      jitter(static_cast<std::size_t>(per_status) + 16);
  Item item;
  LineGuard guard(lines);
  int64_t last_wake = 0;
  can::Frame frame;
  can::BusState bus_state = sock->state();
  can::Counters can_counters = sock->counters();  // as of the last period the socket was here
  std::unique_ptr<rcp::WhiskCycle> used_cycle;

  timespec next;
  clock_gettime(CLOCK_MONOTONIC, &next);
  add_ns(next, period_ns);
  std::string fatal;  // why the loop ended early, if it did
  try {
    while (!core.finished()) {
      while (clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &next, nullptr) == EINTR) {
      }
      // Test-only (WHISKEYE_FAULT_INJECT): a stuck control loop, to prove the watchdog notices.
      service.stall_if_injected(mono_now_us(), [] { return g_stop.load(); });
      const int64_t deadline = timespec_us(next);
      // Both clocks read together: the period's epoch stamp is `woke` plus the wall-clock offset, not
      // shifted by however long draining the socket takes.
      const int64_t woke = mono_now_us();
      const int64_t woke_utime = now_utime();
      wake.add(static_cast<double>(woke - deadline));
      if (last_wake != 0) jitter.add(static_cast<double>(std::llabs(woke - last_wake - period_us)));
      last_wake = woke;
      while (shared.used_cycles.try_pop(used_cycle)) core.recycle(std::move(used_cycle));

      // Drain the socket without waiting. One that went down is handed to the publisher thread to be
      // reopened and comes back in a later period.
      if (!sock && shared.can_socket.take_back(sock)) bus_state = sock->state();
      if (sock) {
        for (int guard = 0; guard < 1024; ++guard) {
          const can::Socket::Rx rx = sock->receive(frame, 0);
          if (rx == can::Socket::Rx::kFrame) {
            core.on_frame(frame.id, frame.fd, frame.payload(), mono_now_us());
          } else if (rx == can::Socket::Rx::kDown) {
            rt_log(shared, LogLevel::kWarning, "whiskerd: %s; reopening", sock->last_error());
            can_counters = sock->counters();
            shared.can_socket.give_up(sock);
            break;
          } else if (rx == can::Socket::Rx::kTimeout) {
            break;
          }
        }
      }

      if (const char* line = core.take_rejection_line()) {
        rt_log(shared, LogLevel::kWarning, "whiskerd: rejected frame: %s (%lld rejected so far; logged at the 1st, 10th, 100th, ...)",
               line, static_cast<long long>(core.rejected_frames()));
      }

      if (sock && sock->state() != bus_state) {
        rt_log(shared, LogLevel::kWarning, "whiskerd: CAN %s %s -> %s", sock->interface().c_str(), can::bus_state_name(bus_state),
               can::bus_state_name(sock->state()));
        bus_state = sock->state();
      }
      if (guard.poll_fault(core)) rt_log(shared, LogLevel::kError, "whiskerd: motor fault / emergency stop: motors disabled");
      if (g_stop.load(std::memory_order_relaxed)) core.request_stop();

      const Safety before = core.safety();
      core.step(woke_utime, woke, item.period);
      if (core.safety() != before) {
        rt_log(shared, core.safety() == Safety::kFault ? LogLevel::kError : LogLevel::kNotice,
               "whiskerd: %s -> %s%s%s%s", safety_name(before), safety_name(core.safety()),
               core.reason()[0] ? " (" : "", core.reason(), core.reason()[0] ? ")" : "");
      }
      if (sock) send_command(*sock, p, item.period.command, core);
      guard.update(core);
      item.kind = Item::Kind::kPeriod;
      if (!shared.ring.try_push(item)) ++core.counters()[Counters::kPublishDrops];

      const int64_t done = mono_now_us();
      loop.add(static_cast<double>(done - woke));
      if (done > deadline + period_us) ++core.counters()[Counters::kDeadlineMisses];
      shared.rt_periods.fetch_add(1, std::memory_order_relaxed);

      if (done >= next_status_mono) {
        next_status_mono += status_period_us;
        if (next_status_mono < done) next_status_mono = done + status_period_us;
        Item st;
        st.kind = Item::Kind::kStatus;
        StatusSnapshot& s = st.status;
        s.utime = now_utime();
        s.safety = core.safety();
        s.reason = core.reason();
        s.bus_state = sock ? can::bus_state_name(sock->state()) : "down";
        s.counters = core.counters().values;
        if (sock) can_counters = sock->counters();
        const can::Counters& cc = can_counters;
        s.can_rx = cc.rx_frames;
        s.can_error_frames = cc.error_frames;
        s.can_bus_off = cc.bus_off;
        s.can_error_passive = cc.error_passive;
        s.can_reopens = cc.reopens;
        s.can_rx_overflow = cc.rx_overflow;
        s.wake_latency = wake.take();
        s.loop_time = loop.take();
        s.period_jitter = jitter.take();
        s.rt_scheduling = rt;
        if (!shared.ring.try_push(st)) ++core.counters()[Counters::kPublishDrops];
      }

      add_ns(next, period_ns);
      // After a stall longer than a period, resynchronise instead of running a burst of late periods.
      if (mono_now_us() > timespec_us(next) + period_us) {
        const int64_t late = mono_now_us() - timespec_us(next);
        core.counters()[Counters::kDeadlineMisses] += late / period_us;
        clock_gettime(CLOCK_MONOTONIC, &next);
        add_ns(next, period_ns);
      }
    }
  } catch (const std::exception& e) {
    fatal = e.what();
  }
  // Whatever happened: the enable line ends low and the boards get a last disabled command, before
  // anything that may block (stderr into a full journal pipe); then say why.
  if (!sock) shared.can_socket.take_back(sock);
  const std::string not_dropped = disable_motors(lines, sock.get(), p, core);
  if (!fatal.empty()) log_error("whiskerd: fatal: " + fatal + "; motors disabled");
  if (!not_dropped.empty()) log_error("whiskerd: the enable line could not be dropped: " + not_dropped);
  if (!fatal.empty() || !not_dropped.empty()) shared.exit_code.store(1);
  shared.rt_done.store(true);
}

void publisher_thread(const Params& p, Bus& bus, Shared& shared, ServiceNotifier& service) {
  Item item;
  whisker_sample_t sample;
  rcp_state_t state;
  whisk_cycle_t cycle;
  driver_status_t status;
  int64_t last_periods = -1;
  bool reopen_failed = false;  // this outage's first failure is logged, not every retry
  while (true) {
    bool any = false;
    while (shared.ring.try_pop(item)) {
      any = true;
      if (item.kind == Item::Kind::kPeriod) {
        to_lcm(item.period, sample, state);
        publish(bus, p.channel_sample, sample);
        publish(bus, p.channel_state, state);
        if (item.period.completed_cycle) {
          to_lcm(*item.period.completed_cycle, cycle);
          publish(bus, p.channel_cycle, cycle);
          shared.used_cycles.try_push(item.period.completed_cycle);
        }
      } else if (item.kind == Item::Kind::kLog) {
        log_line(item.level, item.text.data());
      } else if (item.kind == Item::Kind::kStatus) {
        to_lcm(item.status, status);
        status.counter_names.push_back("lcm_publish_errors");
        status.counter_values.push_back(bus.publish_errors());
        status.num_counters = static_cast<int32_t>(status.counter_names.size());
        publish(bus, p.channel_status, status);
      }
    }
    // After the control thread's log lines, so its "reopening" comes before this "reopened".
    switch (shared.can_socket.service(monotonic_us())) {
      case SocketCustody<can::Socket>::Attempt::kReopened:
        log_notice("whiskerd: CAN " + p.interface + " reopened");
        reopen_failed = false;
        break;
      case SocketCustody<can::Socket>::Attempt::kFailed:
        if (!reopen_failed) {
          log_warning("whiskerd: " + std::string(shared.can_socket.held()->last_error()) + "; retrying, every " +
                      std::to_string(SocketCustody<can::Socket>::kMaxBackoffUs / 1000000) + " s at the most");
        }
        reopen_failed = true;
        break;
      case SocketCustody<can::Socket>::Attempt::kNone: break;
    }
    // Only pet the watchdog while the control loop makes progress: a stuck control thread must get
    // the service restarted even though this thread is fine.
    if (service.watchdog_enabled()) {
      const int64_t periods = shared.rt_periods.load();
      if (periods != last_periods && service.keep_alive(monotonic_us())) last_periods = periods;
    }
    if (!any) {
      if (shared.rt_done.load() && shared.ring.size() == 0) break;
      std::this_thread::sleep_for(std::chrono::milliseconds(1));
    }
  }
}

int run(const Params& params) {
  ServiceNotifier service("whiskerd", monotonic_us());  // a malformed WHISKEYE_FAULT_INJECT: exit 1
  std::unique_ptr<can::Socket> sock;
  std::unique_ptr<gpio::MotorLines> lines;
  std::unique_ptr<LcmBus> bus;
  try {
    sock = std::make_unique<can::Socket>(params.interface, params.mode == wp::BusMode::kFd);
    // The 8-id blocks of samples and heartbeats (base .. base+7; load() rejects a base that is not a
    // multiple of 8): node ids 1..6 plus neighbours, so a misconfigured board (an unknown id next
    // to ours) is counted rather than silently filtered.
    std::vector<can::Filter> filters;
    for (uint32_t base : {params.ids.sample_base, params.ids.heartbeat_base}) filters.push_back({base, 0x7f8});
    sock->set_filters(filters);
    // ~1 s of bus traffic: a stalled control thread loses no frames (they show as stale periods).
    sock->set_receive_buffer(4 << 20);
    if (params.gpio) {
      lines = gpio::open_gpiod_lines(params.lines, "whiskerd");
    } else {
      lines = std::make_unique<gpio::NoMotorLines>();
    }
    bus = std::make_unique<LcmBus>(params.lcm_url);
  } catch (const std::exception& e) {
    log_error(std::string("whiskerd: ") + e.what());
    return 1;
  }
  std::cerr << "whiskerd: " << params.interface << " (" << (params.mode == wp::BusMode::kFd ? "CAN FD" : "classic CAN")
            << ", " << params.rate_hz << " Hz), " << lines->describe() << "\n";

  struct sigaction sa {};
  sa.sa_handler = on_signal;
  sigaction(SIGTERM, &sa, nullptr);
  sigaction(SIGINT, &sa, nullptr);

  auto shared = std::make_unique<Shared>();
  std::thread control([&] { control_thread(params, std::move(sock), *lines, *shared, service); });
  std::thread publisher([&] { publisher_thread(params, *bus, *shared, service); });
  service.ready();
  control.join();
  publisher.join();
  service.stopping();
  std::cerr << "whiskerd: stopped, motors disabled\n";
  return shared->exit_code.load();
}

}  // namespace

int main(int argc, char** argv) {
  cli::Program program("whiskerd",
                       "whiskerd: whisker sensors and motors over SocketCAN, RCP whisking control loop, LCM publisher");
  CLI::App& app = program.app();
  std::string config_path;
  std::string interface;
  std::string lcm_url;
  bool no_gpio = false;
  bool print_config = false;
  program.add_config(config_path, "whiskerd YAML (config/whiskerd.yaml); defaults without it");
  app.add_option("-i,--interface", interface, "CAN interface, overrides can.interface");
  app.add_flag("--no-gpio", no_gpio,
               "run without motor enable / fault lines (rigs without GPIO), overrides gpio.enabled");
  program.add_lcm_url(lcm_url)->description("LCM URL, overrides lcm.url (default: $LCM_DEFAULT_URL, or LCM's default)");
  program.add_print_config(print_config);
  return program.run(argc, argv, [&] {
    // The file, then the command line's overrides: what is printed is what runs.
    ParamNode root = config_path.empty() ? ParamNode::empty() : ParamNode::from_file(config_path);
    if (!interface.empty()) root.set_override("can.interface", interface, "--interface");
    if (no_gpio) root.set_override("gpio.enabled", "false", "--no-gpio");
    if (!lcm_url.empty()) root.set_override("lcm.url", lcm_url, "--lcm-url");
    Params params;
    load(root, params);  // a ParamError: exit 2
    if (print_config) {
      std::cout << root.dump();
      return 0;
    }
    std::cerr << root.dump();
    return run(params);
  });
}
