// NotifyListener and the watchdog check; see notify_probe.h.
#include "notify_probe.h"

#include "subprocess.h"

#include <poll.h>
#include <sys/socket.h>
#include <sys/un.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cstring>
#include <sstream>
#include <stdexcept>

#include <whiskeye/common/clock.h>
#include <whiskeye/common/utime.h>

namespace whiskeye::deploy_testing {

NotifyListener::NotifyListener() {
  static std::atomic<int> counter{0};
  path_ = "/tmp/whiskeye-notify-" + std::to_string(::getpid()) + "-" + std::to_string(counter++) + ".sock";
  ::unlink(path_.c_str());
  fd_ = ::socket(AF_UNIX, SOCK_DGRAM | SOCK_CLOEXEC, 0);
  if (fd_ < 0) throw std::runtime_error(std::string("socket(AF_UNIX): ") + std::strerror(errno));
  sockaddr_un addr{};
  addr.sun_family = AF_UNIX;
  std::strncpy(addr.sun_path, path_.c_str(), sizeof(addr.sun_path) - 1);
  if (::bind(fd_, reinterpret_cast<sockaddr*>(&addr), sizeof(addr)) != 0) {
    ::close(fd_);
    throw std::runtime_error("bind " + path_ + ": " + std::strerror(errno));
  }
  thread_ = std::thread([this] { run(); });
}

NotifyListener::~NotifyListener() {
  stop_ = true;
  thread_.join();
  ::close(fd_);
  ::unlink(path_.c_str());
}

void NotifyListener::run() {
  char buf[4096];
  while (!stop_) {
    pollfd p{fd_, POLLIN, 0};
    if (::poll(&p, 1, 20) <= 0) continue;
    const ssize_t n = ::recv(fd_, buf, sizeof(buf), 0);
    if (n <= 0) continue;
    const int64_t t = monotonic_us();
    std::istringstream lines(std::string(buf, static_cast<std::size_t>(n)));
    std::string line;
    std::lock_guard<std::mutex> lock(mutex_);
    while (std::getline(lines, line)) {
      if (!line.empty()) messages_.push_back({t, line});
    }
  }
}

std::vector<NotifyListener::Message> NotifyListener::messages() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return messages_;
}

std::vector<int64_t> NotifyListener::times_of(const std::string& text) const {
  std::vector<int64_t> out;
  std::lock_guard<std::mutex> lock(mutex_);
  for (const auto& m : messages_) {
    if (m.text == text) out.push_back(m.mono_us);
  }
  return out;
}

std::string WatchdogReport::summary() const {
  std::ostringstream s;
  s << "ready=" << ready << " after " << ready_after_s << " s; " << pings_in_window << " keep-alives in the window, max gap "
    << max_gap_s << " s; stall logged=" << stall_logged << ", then " << pings_after_stall << " keep-alives in " << quiet_s
    << " s, alive=" << alive_while_stalled << "; exit " << exit_code << ", STOPPING=1 " << stopping_sent;
  for (const auto& p : problems) s << "\n  problem: " << p;
  return s.str();
}

WatchdogReport check_watchdog(const std::vector<std::string>& argv, const WatchdogCheck& c,
                              const std::vector<std::string>& extra_env) {
  using whiskeye::testing::Subprocess;
  using whiskeye::testing::wait_until;
  WatchdogReport r;
  NotifyListener listener;
  std::vector<std::string> env = extra_env;
  env.push_back("NOTIFY_SOCKET=" + listener.path());
  env.push_back("WATCHDOG_USEC=" + std::to_string(c.watchdog_usec));
  std::ostringstream stall;
  stall << "WHISKEYE_FAULT_INJECT=" << c.fault << "=" << c.stall_after_s << "s";
  env.push_back(stall.str());
  const int64_t interval_us = c.watchdog_usec / 2;

  const int64_t t0 = monotonic_us();
  Subprocess daemon(argv, "", env);
  r.ready = wait_until([&] { return !listener.times_of("READY=1").empty() || !daemon.running(); }, c.ready_timeout_s) &&
            !listener.times_of("READY=1").empty();
  if (!r.ready) {
    r.problems.push_back("no READY=1 within " + std::to_string(c.ready_timeout_s) + " s" +
                         (daemon.running() ? "" : " (the daemon exited)"));
    r.output = daemon.output();
    return r;
  }
  const int64_t ready_us = listener.times_of("READY=1").front();
  r.ready_after_s = static_cast<double>(ready_us - t0) * 1e-6;
  const int64_t window_end = ready_us + static_cast<int64_t>(c.window_s * 1e6);
  if (window_end + interval_us > t0 + static_cast<int64_t>(c.stall_after_s * 1e6)) {
    r.problems.push_back("READY=1 came too late to measure keep-alives before the stall (raise stall_after_s)");
  }

  // Phase 1: regular keep-alives between READY=1 and the end of the window.
  std::this_thread::sleep_for(std::chrono::microseconds(std::max<int64_t>(0, window_end - monotonic_us())));
  std::vector<int64_t> in_window;
  for (int64_t t : listener.times_of("WATCHDOG=1")) {
    if (t >= ready_us && t <= window_end) in_window.push_back(t);
  }
  r.pings_in_window = static_cast<int>(in_window.size());
  int64_t prev = ready_us;
  for (int64_t t : in_window) {
    r.max_gap_s = std::max(r.max_gap_s, static_cast<double>(t - prev) * 1e-6);
    prev = t;
  }
  r.max_gap_s = std::max(r.max_gap_s, static_cast<double>(window_end - prev) * 1e-6);
  const double expected = c.window_s * 1e6 / static_cast<double>(interval_us);
  if (r.pings_in_window < static_cast<int>(expected * 0.5)) {
    r.problems.push_back("too few keep-alives: " + std::to_string(r.pings_in_window) + " in " +
                         std::to_string(c.window_s) + " s, expected about " + std::to_string(expected));
  }
  // Faster than every interval/2 would mean the daemon ignores WATCHDOG_USEC.
  if (r.pings_in_window > static_cast<int>(expected * 2.0) + 1) {
    r.problems.push_back("too many keep-alives: " + std::to_string(r.pings_in_window) + ", expected about " +
                         std::to_string(expected));
  }
  if (r.max_gap_s > c.max_gap_factor * static_cast<double>(c.watchdog_usec) * 1e-6) {
    r.problems.push_back("gap of " + std::to_string(r.max_gap_s) + " s between keep-alives (WATCHDOG_USEC " +
                         std::to_string(c.watchdog_usec * 1e-6) + " s)");
  }

  // Phase 2: the stall. Keep-alives may still be in flight for one interval after the log line, and
  // for the grace a worker thread's stall needs to be noticed.
  r.stall_logged = wait_until([&] { return daemon.output().find(c.stall_log) != std::string::npos; },
                              c.stall_after_s + 10.0);
  if (!r.stall_logged) {
    r.problems.push_back("the daemon never logged the injected stall");
  } else {
    const int64_t stalled_us = monotonic_us() + interval_us + seconds_to_utime(c.stall_grace_s);
    const int64_t quiet_us = 3 * c.watchdog_usec;
    std::this_thread::sleep_for(std::chrono::microseconds(stalled_us - monotonic_us() + quiet_us));
    r.quiet_s = static_cast<double>(monotonic_us() - stalled_us) * 1e-6;
    for (int64_t t : listener.times_of("WATCHDOG=1")) {
      if (t > stalled_us) ++r.pings_after_stall;
    }
    r.alive_while_stalled = daemon.running();
    if (r.pings_after_stall > 0) {
      r.problems.push_back(std::to_string(r.pings_after_stall) + " keep-alives while stalled (" + c.fault + ")");
    }
    if (!r.alive_while_stalled) r.problems.push_back("the daemon died instead of stalling");
  }

  // Phase 3: an interrupt ends the stall and the daemon shuts down normally.
  r.exit_code = daemon.stop(10.0, SIGINT);
  r.stopping_sent = !listener.times_of("STOPPING=1").empty();
  if (r.exit_code != 0) r.problems.push_back("exit code " + std::to_string(r.exit_code) + " after SIGINT");
  if (!r.stopping_sent) r.problems.push_back("no STOPPING=1 on the way out");
  r.output = daemon.output();
  return r;
}

}  // namespace whiskeye::deploy_testing
