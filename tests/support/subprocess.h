// A child process for integration tests: fork/exec with stdout+stderr captured to a file, wait with a
// timeout, signalled and reaped on destruction so a failing test never leaves processes behind, and
// killed when the test process dies without running destructors (a ctest timeout, an abort).
#pragma once

#include <csignal>
#include <cstdint>
#include <string>
#include <vector>

namespace whiskeye::testing {

class Subprocess {
 public:
  // Starts argv[0] (searched in PATH) with the given arguments; output goes to `output_path`
  // (empty: a temp file, removed on destruction). Extra environment entries "K=V" are added to the
  // child's environment.
  explicit Subprocess(const std::vector<std::string>& argv, std::string output_path = "",
                      const std::vector<std::string>& extra_env = {});
  ~Subprocess();
  Subprocess(const Subprocess&) = delete;
  Subprocess& operator=(const Subprocess&) = delete;

  // Waits up to timeout_s; returns the exit code, 128+signal if killed by a signal, -1 on timeout.
  int wait(double timeout_s);
  bool running();
  void signal(int sig);
  // Sends SIGINT, waits up to timeout_s, then SIGKILL. Returns the exit status as wait().
  int stop(double timeout_s = 5.0, int sig = SIGINT);
  std::string output() const;
  int pid() const { return pid_; }

 private:
  int pid_ = -1;
  int status_ = -1;
  bool reaped_ = false;
  std::string output_path_;
  bool owns_output_ = false;  // a temp file of ours: removed with the process
};

// A memory field of /proc/PID/status in kB ("VmRSS", "VmHWM"), -1 when it cannot be read.
int64_t proc_status_kb(int pid, const std::string& field);

// Polls `pred` every 10 ms until true or timeout; returns its last value.
template <typename Pred>
bool wait_until(Pred pred, double timeout_s);

}  // namespace whiskeye::testing

#include <chrono>
#include <thread>

template <typename Pred>
bool whiskeye::testing::wait_until(Pred pred, double timeout_s) {
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::duration<double>(timeout_s);
  while (std::chrono::steady_clock::now() < deadline) {
    if (pred()) return true;
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  return pred();
}
