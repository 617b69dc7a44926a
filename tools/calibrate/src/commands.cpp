// whiskeye-calibrate's subcommands (see commands.h).
#include "whiskeye/calibrate/commands.h"

#include <whiskeye/common/cli.h>
#include <whiskeye/common/config_path.h>
#include <whiskeye/common/input_file.h>
#include <whiskeye/common/output_file.h>
#include <whiskeye/common/params.h>
#include <whiskeye/common/printable.h>

#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <chrono>
#include <cstring>
#include <ctime>
#include <functional>
#include <iostream>
#include <mutex>
#include <stdexcept>
#include <thread>

#include "whiskeye/calibrate/estimators.h"
#include "whiskeye/calibrate/sweep.h"
#include "whiskeye/can/can_socket.h"
#include "whiskeye/can/candump.h"
#include "whiskeye/whiskerd/config.h"

namespace whiskeye::calibrate {

namespace {

constexpr const char* kProgram = "whiskeye-calibrate";

struct Setup {
  whiskerd::Params params;
  std::string config;
};

// whiskerd's configuration as whiskerd would run with it: the file, then its drop-ins.
Setup load_setup(const Options& o, std::string* printed = nullptr) {
  Setup s;
  s.config = o.config.empty() ? default_config_path("whiskerd.yaml", "--config").string() : o.config;
  const std::string text = whiskerd::load_with_dropins(ParamNode::from_file(s.config), s.config, s.params);
  if (printed) *printed = text;
  return s;
}

// A subcommand that writes a drop-in refuses a bad -o before it listens or reads: one that is the log
// or the config it reads, that cannot be replaced atomically (a FIFO, a link, a missing directory),
// or that whiskerd would never read (20-rest.yml; whiskerd.d itself, its directory missing).
void check_output(const Options& o, const Setup& s) {
  if (o.output.empty()) return;
  cli::refuse_output_onto_input("-o", o.output, {{"--input", o.input}, {"--config", s.config}});
  cli::refuse_unwritable_output("-o", o.output);
  if (!whiskerd::is_dropin_name(o.output)) {
    throw cli::UsageError("-o " + o.output + ": whiskerd would not read it: its drop-ins are NAME.yaml files in " +
                          whiskerd::dropin_dir(s.config).string() + "/ (e.g. 20-rest.yaml)");
  }
}

// The seconds a recording spans (Recording::span_us) plus one sample period (`fallback` if empty).
double span_s(const Recording& r, double rate_hz, double fallback) {
  if (r.first_utime() < 0) return fallback;
  return static_cast<double>(r.span_us()) / 1e6 + 1.0 / rate_hz;
}

// A candump -l log into `r`; returns the seconds it spans. Only a regular file is read (a FIFO, a
// device, a /proc file: open_input_file), and at most kMaxCandumpLineBytes of a line is held. A line
// that is not a CAN frame of the log format, or is longer: runtime_error naming the file and the
// line. Extended-id and remote frames are skipped, as listening on the bus skips them.
double read_log(const std::string& path, Recording& r, double rate_hz) {
  const InputFile file = open_input_file(path, "candump log");
  struct Closer {
    int fd;
    ~Closer() { ::close(fd); }
  } closer{file.fd};
  can::CandumpLines lines;
  can::LoggedFrame f;
  std::string interface;
  const auto take = [&](int64_t number, std::string_view line) {
    switch (can::classify_candump_line(line, f, interface)) {
      case can::CandumpLine::kFrame: r.add_frame(f.utime, f.id, f.fd, f.data); break;
      case can::CandumpLine::kErrorFrame: r.add_error_frame(f.utime); break;
      case can::CandumpLine::kOther:
      case can::CandumpLine::kBlank: break;
      case can::CandumpLine::kInvalid:
        throw std::runtime_error(path + ":" + std::to_string(number) + ": not a candump -l line: " + printable(line));
    }
  };
  std::vector<char> buffer(64 * 1024);
  for (;;) {
    const ssize_t got = ::read(file.fd, buffer.data(), buffer.size());
    if (got < 0 && errno == EINTR) continue;
    if (got < 0) throw std::runtime_error(path + ": cannot read the candump log: " + std::strerror(errno));
    if (got == 0) break;
    if (!lines.feed(std::string_view(buffer.data(), static_cast<std::size_t>(got)), take)) {
      throw std::runtime_error(path + ":" + std::to_string(lines.too_long()) + ": not a candump -l line: longer than " +
                               std::to_string(can::kMaxCandumpLineBytes) + " bytes");
    }
  }
  lines.finish(take);
  if (r.first_utime() < 0) throw std::runtime_error(path + ": no CAN frame in the log");
  return span_s(r, rate_hz, 0.0);
}

// Listens on the bus (this socket never sends) until `stop` says so, into `r` under `lock`.
void listen(const std::string& interface, Recording& r, std::mutex& lock, const std::function<bool()>& stop,
            const char* motors = "motors off") {
  can::Socket sock(interface);
  sock.set_receive_buffer(4 << 20);
  std::cerr << kProgram << ": listening on " << interface << " (" << motors << ")\n";
  can::Frame frame;
  while (!stop()) {
    const can::Socket::Rx rx = sock.receive(frame, 100000);
    const std::lock_guard<std::mutex> guard(lock);
    if (rx == can::Socket::Rx::kFrame && !frame.extended && !frame.rtr) {
      r.add_frame(frame.rx_utime, frame.id, frame.fd, frame.payload());
    } else if (rx == can::Socket::Rx::kErrorFrame) {
      r.add_error_frame(frame.rx_utime);
    } else if (rx == can::Socket::Rx::kDown) {
      throw std::runtime_error("CAN " + interface + ": the interface went down");
    }
  }
}

bool any_fault(const Recording& r) {
  for (int b = 0; b < wp::kNumBoards; ++b) {
    if (r.board(b).fault_samples > 0) return true;
  }
  return false;
}

// The recording of --input, or of --seconds on the bus. Returns the seconds it spans.
double record(const Options& o, const Setup& s, Recording& r) {
  if (!o.input.empty()) return read_log(o.input, r, s.params.rate_hz);
  const std::string interface = o.interface.empty() ? s.params.interface : o.interface;
  std::mutex lock;
  const auto until = std::chrono::steady_clock::now() + std::chrono::duration<double>(o.seconds);
  listen(interface, r, lock, [&] { return std::chrono::steady_clock::now() >= until; });
  return span_s(r, s.params.rate_hz, o.seconds);
}

// Prints the table; refuses (exit 1) on problems or implausible values; else writes the drop-in
// (or prints it without -o).
int finish(const char* what, const Options& o, const Setup& s, Result result) {
  const Problems bounds = check_bounds(result.estimates);
  result.problems.insert(result.problems.end(), bounds.begin(), bounds.end());
  std::cout << format_table(result.estimates);
  if (!result.problems.empty()) {
    for (const std::string& p : result.problems) std::cerr << kProgram << ": " << what << ": " << p << "\n";
    std::cerr << kProgram << ": " << what << ": nothing written\n";
    return cli::kExitFailure;
  }
  const std::time_t now = std::time(nullptr);
  char stamp[32];
  std::strftime(stamp, sizeof stamp, "%Y-%m-%d %H:%M:%S UTC", std::gmtime(&now));
  const std::string text = whiskerd::format_dropin(
      dropin_entries(result.estimates),
      std::string("whiskeye-calibrate ") + what + ", " + stamp + ", from " +
          (o.input.empty() ? "the bus" : o.input) + " (calibration in use: " + s.config + " and its drop-ins)");
  if (o.output.empty()) {
    std::cout << text;
    return cli::kExitOk;
  }
  // whiskerd reads it: the old drop-in or the new one, never part (a full disk, a kill, two runs at once).
  write_file_atomically(o.output, text);
  std::cerr << kProgram << ": " << what << ": wrote " << o.output << "\n";
  return cli::kExitOk;
}

}  // namespace

int print_config(const Options& o) {
  std::string printed;
  load_setup(o, &printed);
  std::cout << printed;
  return cli::kExitOk;
}

int run_bus(const Options& o) {
  const Setup s = load_setup(o);
  Recording r(s.params.mode, s.params.ids);
  const double seconds = record(o, s, r);
  const BusReport rep = check_bus(r, s.params.rate_hz, seconds);
  std::cout << format_bus_report(rep);
  return rep.ok ? cli::kExitOk : cli::kExitFailure;
}

int run_rest(const Options& o) {
  const Setup s = load_setup(o);
  check_output(o, s);
  Recording r(s.params.mode, s.params.ids);
  record(o, s, r);
  return finish("rest", o, s, estimate_rest(r, s.params, RestLimits{}));
}

int run_map(const Options& o) {
  const Setup s = load_setup(o);
  check_output(o, s);
  Recording r(s.params.mode, s.params.ids);
  std::vector<int> order = o.expect;
  if (order.empty()) {
    for (int w = 0; w < kNumWhiskers; ++w) order.push_back(w);
  }
  if (!o.input.empty()) {
    read_log(o.input, r, s.params.rate_hz);
    return finish("map", o, s, map_whiskers(find_pushes(r), order, s.params));
  }
  // Interactive: the bus is recorded in the background while the operator pushes each whisker; after
  // each Enter the pushes found so far are shown.
  const std::string interface = o.interface.empty() ? s.params.interface : o.interface;
  std::mutex lock;
  std::atomic<bool> done{false};
  std::exception_ptr failure;
  std::thread listener([&] {
    try {
      listen(interface, r, lock, [&] { return done.load(); });
    } catch (...) {
      failure = std::current_exception();
      done = true;
    }
  });
  std::cout << "Hands off the whiskers for 2 s...\n" << std::flush;
  std::this_thread::sleep_for(std::chrono::seconds(2));
  std::size_t shown = 0;
  for (int w : order) {
    std::cout << "Push " << whisker_name(w) << " forward (+x) and release, then up (+y) and release; then press Enter: "
              << std::flush;
    std::string ignored;
    if (!std::getline(std::cin, ignored) || done) break;
    std::vector<Push> pushes;
    {
      const std::lock_guard<std::mutex> guard(lock);
      pushes = find_pushes(r);
    }
    for (; shown < pushes.size(); ++shown) {
      const Push& p = pushes[shown];
      std::cout << "  moved: channel " << p.channel << " (board " << p.channel / 4 << "), sensor x " << p.dx
                << ", y " << p.dy << " counts\n";
    }
  }
  done = true;
  listener.join();
  if (failure) std::rethrow_exception(failure);
  return finish("map", o, s, map_whiskers(find_pushes(r), order, s.params));
}

int run_gain(const Options& o) {
  if (!(o.deflection > 0.0 && o.deflection < 1.0)) throw cli::UsageError("gain: --deflection D (0 < D < 1) is required");
  const Setup s = load_setup(o);
  check_output(o, s);
  Recording r(s.params.mode, s.params.ids);
  record(o, s, r);
  return finish("gain", o, s, fit_gains(find_pushes(r), o.expect, o.deflection, s.params));
}

int run_theta(const Options& o) {
  const Setup s = load_setup(o);
  check_output(o, s);
  Recording r(s.params.mode, s.params.ids);
  const double stop = o.stop_deg > 0 ? o.stop_deg * kPi / 180.0 : s.params.controller.pattern.theta_limit;
  if (!o.input.empty()) {
    record(o, s, r);
  } else {
    // whiskerd's control loop sweeps; a second socket records what the boards report.
    const std::string interface = o.interface.empty() ? s.params.interface : o.interface;
    std::mutex lock;
    const SweepOutcome swept = run_sweep(s.params, {stop, 0.1, o.sweep_seconds, interface, !o.no_gpio},
                                         [&](const std::function<bool()>& until) {
                                           // Any fault a board reports ends the sweep at once.
                                           listen(interface, r, lock,
                                                  [&] { return until() || any_fault(r); }, "whiskerd sweeping");
                                         });
    if (!swept.abort.empty()) {
      std::cerr << kProgram << ": theta: sweep interrupted: " << swept.abort << "; nothing written\n";
      return cli::kExitFailure;
    }
  }
  return finish("theta", o, s, fit_theta(r, stop, s.params));
}

}  // namespace whiskeye::calibrate
