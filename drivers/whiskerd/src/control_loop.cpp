// whiskerd's control thread (ControlLoop) and publisher thread (publish_loop); see control_loop.h.
#include "whiskeye/whiskerd/control_loop.h"
#include "whiskeye/whiskerd/lcm.h"

#include "whiskeye/common/clock.h"

#include <pthread.h>
#include <sched.h>
#include <sys/mman.h>

#include <whiskeye/driver_status_t.hpp>
#include <whiskeye/rcp_state_t.hpp>
#include <whiskeye/whisk_cycle_t.hpp>
#include <whiskeye/whisker_sample_t.hpp>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cstdarg>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <iostream>
#include <thread>

namespace whiskeye::whiskerd {
namespace {

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

}  // namespace

ControlLoop::ControlLoop(const Params& p, std::unique_ptr<can::Socket> sock, gpio::MotorLines& lines, Shared& shared,
                         ServiceNotifier& service, const std::atomic<bool>& stop)
    : p_(p),
      rt_(make_realtime(p)),
      sock_(std::move(sock)),
      lines_(lines),
      shared_(shared),
      service_(service),
      stop_(stop),
      core_(p),
      period_ns_(static_cast<int64_t>(1e9 / p.rate_hz)),
      period_us_(period_ns_ / 1000),
      per_status_(std::max(1, static_cast<int>(p.status_period_s * p.rate_hz))),
      status_period_us_(static_cast<int64_t>(p.status_period_s * 1e6)),
      next_status_mono_(mono_now_us() + status_period_us_),
      wake_(static_cast<std::size_t>(per_status_) + 16),
      loop_(static_cast<std::size_t>(per_status_) + 16),
      jitter_(static_cast<std::size_t>(per_status_) + 16),
      guard_(lines),
      bus_state_(sock_->state()),
      can_counters_(sock_->counters()) {
  clock_gettime(CLOCK_MONOTONIC, &next_);
  add_ns(next_, period_ns_);
}

void ControlLoop::log(LogLevel level, const char* fmt, ...) {
  log_item_.kind = Item::Kind::kLog;
  log_item_.level = level;
  va_list args;
  va_start(args, fmt);
  std::vsnprintf(log_item_.text.data(), log_item_.text.size(), fmt, args);
  va_end(args);
  shared_.ring.try_push(log_item_);  // a full ring loses the line, never blocks
}

void ControlLoop::send_command(const wp::MotorCommand& cmd) {
  wp::encode_command(cmd, p_.mode, p_.ids, command_frames_);
  can::Frame f;
  for (int i = 0; i < command_frames_.count; ++i) {
    const wp::CommandFrame& c = command_frames_.frames[static_cast<std::size_t>(i)];
    f.fd = c.fd;
    f.brs = c.fd;
    f.id = c.id;
    f.len = c.len;
    std::copy_n(c.data.begin(), c.len, f.data.begin());
    if (!sock_->send(f)) ++core_.counters()[Counters::kCanTxErrors];
  }
}

std::string ControlLoop::disable_motors() {
  std::string error;
  try {
    lines_.set_enable(false);
  } catch (const std::exception& e) {
    error = e.what();
  }
  if (sock_ != nullptr && sock_->is_open()) {
    wp::MotorCommand off;
    send_command(off);
  }
  return error;
}

void ControlLoop::run() {
  std::string fatal;  // why the loop ended early, if it did
  try {
    while (!core_.finished()) period();
  } catch (const std::exception& e) {
    fatal = e.what();
  }
  // Whatever happened: the enable line ends low and the boards get a last disabled command, before
  // anything that may block (stderr into a full journal pipe); then say why.
  if (!sock_) shared_.can_socket.take_back(sock_);
  const std::string not_dropped = disable_motors();
  if (!fatal.empty()) log_error("whiskerd: fatal: " + fatal + "; motors disabled");
  if (!not_dropped.empty()) log_error("whiskerd: the enable line could not be dropped: " + not_dropped);
  if (!fatal.empty() || !not_dropped.empty()) shared_.exit_code.store(1);
  shared_.rt_done.store(true);
}

void ControlLoop::receive_frames() {
  // Drain the socket without waiting. One that went down is handed to the publisher thread to be
  // reopened and comes back in a later period.
  if (!sock_ && shared_.can_socket.take_back(sock_)) bus_state_ = sock_->state();
  if (!sock_) return;
  for (int n = 0; n < 1024; ++n) {
    const can::Socket::Rx rx = sock_->receive(frame_, 0);
    if (rx == can::Socket::Rx::kFrame) {
      core_.on_frame(frame_.id, frame_.fd, frame_.payload(), mono_now_us());
    } else if (rx == can::Socket::Rx::kDown) {
      log(LogLevel::kWarning, "whiskerd: %s; reopening", sock_->last_error());
      can_counters_ = sock_->counters();
      shared_.can_socket.give_up(sock_);
      break;
    } else if (rx == can::Socket::Rx::kTimeout) {
      break;
    }
  }
}

void ControlLoop::period() {
  while (clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &next_, nullptr) == EINTR) {
  }
  // Test-only (WHISKEYE_FAULT_INJECT): a stuck control loop, to prove the watchdog notices.
  service_.stall_if_injected(mono_now_us(), [this] { return stop_.load(); });
  const int64_t deadline = timespec_us(next_);
  // Both clocks read together: the period's epoch stamp is `woke` plus the wall-clock offset, not
  // shifted by however long draining the socket takes.
  const int64_t woke = mono_now_us();
  const int64_t woke_utime = now_utime();
  wake_.add(static_cast<double>(woke - deadline));
  if (last_wake_ != 0) jitter_.add(static_cast<double>(std::llabs(woke - last_wake_ - period_us_)));
  last_wake_ = woke;
  while (shared_.used_cycles.try_pop(used_cycle_)) core_.recycle(std::move(used_cycle_));

  receive_frames();

  if (const char* line = core_.take_rejection_line()) {
    log(LogLevel::kWarning, "whiskerd: rejected frame: %s (%lld rejected so far; logged at the 1st, 10th, 100th, ...)", line,
        static_cast<long long>(core_.rejected_frames()));
  }

  if (sock_ && sock_->state() != bus_state_) {
    log(LogLevel::kWarning, "whiskerd: CAN %s %s -> %s", sock_->interface().c_str(), can::bus_state_name(bus_state_),
        can::bus_state_name(sock_->state()));
    bus_state_ = sock_->state();
  }
  if (guard_.poll_fault(core_)) log(LogLevel::kError, "whiskerd: motor fault / emergency stop: motors disabled");
  if (stop_.load(std::memory_order_relaxed)) core_.request_stop();

  const Safety before = core_.safety();
  core_.step(woke_utime, woke, item_.period);
  if (core_.safety() != before) {
    log(core_.safety() == Safety::kFault ? LogLevel::kError : LogLevel::kNotice, "whiskerd: %s -> %s%s%s%s", safety_name(before), safety_name(core_.safety()), core_.reason()[0] ? " (" : "",
        core_.reason(), core_.reason()[0] ? ")" : "");
  }
  if (sock_) send_command(item_.period.command);
  guard_.update(core_);
  item_.kind = Item::Kind::kPeriod;
  if (!shared_.ring.try_push(item_)) ++core_.counters()[Counters::kPublishDrops];

  const int64_t done = mono_now_us();
  loop_.add(static_cast<double>(done - woke));
  if (done > deadline + period_us_) ++core_.counters()[Counters::kDeadlineMisses];
  shared_.rt_periods.fetch_add(1, std::memory_order_relaxed);

  if (done >= next_status_mono_) push_status(done);

  add_ns(next_, period_ns_);
  // After a stall longer than a period, resynchronise instead of running a burst of late periods.
  if (mono_now_us() > timespec_us(next_) + period_us_) {
    const int64_t late = mono_now_us() - timespec_us(next_);
    core_.counters()[Counters::kDeadlineMisses] += late / period_us_;
    clock_gettime(CLOCK_MONOTONIC, &next_);
    add_ns(next_, period_ns_);
  }
}

void ControlLoop::push_status(int64_t done) {
  next_status_mono_ += status_period_us_;
  if (next_status_mono_ < done) next_status_mono_ = done + status_period_us_;
  Item st;
  st.kind = Item::Kind::kStatus;
  StatusSnapshot& s = st.status;
  s.utime = now_utime();
  s.safety = core_.safety();
  s.reason = core_.reason();
  s.bus_state = sock_ ? can::bus_state_name(sock_->state()) : "down";
  s.counters = core_.counters().values;
  if (sock_) can_counters_ = sock_->counters();
  const can::Counters& cc = can_counters_;
  s.can_rx = cc.rx_frames;
  s.can_error_frames = cc.error_frames;
  s.can_bus_off = cc.bus_off;
  s.can_error_passive = cc.error_passive;
  s.can_reopens = cc.reopens;
  s.can_rx_overflow = cc.rx_overflow;
  s.wake_latency = wake_.take();
  s.loop_time = loop_.take();
  s.period_jitter = jitter_.take();
  s.rt_scheduling = rt_;
  if (!shared_.ring.try_push(st)) ++core_.counters()[Counters::kPublishDrops];
}

void publish_loop(const Params& p, Bus& bus, Shared& shared, ServiceNotifier& service) {
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

}  // namespace whiskeye::whiskerd
